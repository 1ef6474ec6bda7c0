"""Where and how the work runs: processes, progress, memory and cached results.

Owns the machinery that is about running a computation, never about what it computes:

* :mod:`~prs_geom.runtime.pool`: the worker-process pool of a build and its background
  jobs (loky processes that forward Ctrl-C to the main process and die with it);
* :mod:`~prs_geom.runtime.scaleout`: the chunked parallel map of the studies (serial,
  joblib or Dask; the same results bit for bit on any of them);
* :mod:`~prs_geom.runtime.progress`: the progress callback protocol and the console display;
* :mod:`~prs_geom.runtime.memwatch`: the guard of a build's resident memory while it runs;
* :mod:`~prs_geom.runtime.cache`: a keyed, checksummed, atomically written store of arrays
  on disk; the caller supplies the key material (:mod:`prs_geom.analysis.fe.cache` keys the
  finite-element influence matrices);
* :mod:`~prs_geom.runtime.stage_cache`: a build stage's results, warnings and files as a
  record of that store (no pickles; files kept once per content), which a rebuild restores
  instead of running the stage (:mod:`prs_geom.build_cache` keys them).

Any layer may use the runtime; the runtime uses nothing of the package above the model
layer (its errors and its atomic file write), with the one exception recorded in the
import-linter contracts (pyproject.toml): the memory watch raises the memory budget's own
error. Importing this package imports none of its modules.
"""
__all__: list[str] = []
