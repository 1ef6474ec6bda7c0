"""Cost of the rating stage (issue 16) in the default build.

Run:  python benchmarks/bench_rating.py

Prints (best of several runs; absolute times only for orientation, the ratios are the result):
* ``analyse_rating`` on the default design with the contact and load model prepared (the
  numbers of the stage: rings, ratings, one batched solve of every variant and load), and
  with a two-case spectrum;
* ``plot_rating`` (the three-panel figure, PNG and SVG) with matplotlib warmed up, as in a
  build where the loads plots ran before it;
* the stage in a whole default build (``report.json`` ``timings_s.rating``) against the build
  time, and the build time without the stage (the stage removed from the stage list), as the
  ratio with / without: after one discarded build (imports, caches), best of three
  alternating pairs. On a shared machine the build time varies by more than the stage costs;
  the stage's own time is the figure to read.
"""
from __future__ import annotations

import tempfile
from pathlib import Path

from timing import best_time, run_timed

from prs_geom import pipeline
from prs_geom.analysis.contact import analyse_contact
from prs_geom.analysis.loads import build_model
from prs_geom.analysis.rating import analyse_rating, rating_case
from prs_geom.exports.plots import plot_rating, save_figure
from prs_geom.model.design import default_design
from prs_geom.model.spectrum import LoadCase, Spectrum


def build_time(stages) -> tuple[float, float]:
    """Seconds of one default build with ``stages`` and the rating stage's own seconds."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out"
        times, ctx = run_timed(lambda: pipeline.run_stages(default_design(), out, stages=stages), 1)
        return times[0], ctx.report["timings_s"].get("rating", 0.0)


def main() -> None:
    d = default_design()
    c = analyse_contact(d)
    m = build_model(d, c)
    analyse_rating(d, c, m)                                   # the calibration constant, once per process
    t_num = best_time(lambda: analyse_rating(d, c, m), 7)
    duty = Spectrum((LoadCase(8000.0, 0.5, 300.0), LoadCase(20000.0, 0.5, 100.0)))
    case = rating_case(d, duty)
    t_spec = best_time(lambda: analyse_rating(d, c, m, case), 7)
    res = analyse_rating(d, c, m)
    import matplotlib.pyplot as plt

    with tempfile.TemporaryDirectory() as tmp:
        fig, ax = plt.subplots()
        ax.plot([0, 1])
        save_figure(fig, Path(tmp), "warm")
        t_plot = best_time(lambda: plot_rating(Path(tmp), d.name, res.curves, {}), 5)
    print(f"analyse_rating (model prepared):      {t_num * 1e3:8.1f} ms")
    print(f"analyse_rating with a 2-case spectrum: {t_spec * 1e3:8.1f} ms")
    print(f"plot_rating (PNG + SVG):               {t_plot * 1e3:8.1f} ms")

    without = [s for s in pipeline.STAGES if s[0] != "rating"]
    build_time(pipeline.STAGES)                               # imports and caches of a first build
    runs = [(build_time(pipeline.STAGES), build_time(without)) for _ in range(3)]
    t_with = min(r[0][0] for r in runs)
    t_without = min(r[1][0] for r in runs)
    t_stage = min(r[0][1] for r in runs)
    print(f"default build with the rating stage:    {t_with:7.2f} s (stage {t_stage:.3f} s)")
    print(f"default build without it:               {t_without:7.2f} s")
    print(f"ratio with / without: {t_with / t_without:.3f}; stage / build: {t_stage / t_with:.3f}")


if __name__ == "__main__":
    main()
