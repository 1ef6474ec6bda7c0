"""The build pipeline and the Python API: design -> analysis -> meshes -> checks -> exports.

Each stage computes its result once and keeps it in the typed
:class:`~prs_geom.exports.report.BuildResults` of the :class:`BuildContext`
(``ctx.results.contact``, ``ctx.results.loads``, ``ctx.results.meshes``, ...); later stages
and the exporters take those objects, never another stage's files. ``report.json`` and
``report.html`` are rendered from them by the export layer
(:func:`prs_geom.exports.report.report_dict`, :func:`prs_geom.exports.html.write_html`).

``build`` runs every stage available on a design and writes all exports plus
``report.json`` into an output folder atomically (:mod:`prs_geom.exports.output`); stages
run in the order of :data:`STAGES` (:data:`HARMONIC_STAGES` for the harmonic drive).

The functions :func:`load_any_design`, :func:`analyse`, :func:`design_pitch`,
:func:`build_meshes` and :func:`build` are the public Python API (``prs_geom.analyse`` and
so on, see README "Python API").
"""
from __future__ import annotations

import contextlib
import json
import shutil
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable

import numpy as np
from numpy.typing import NDArray

from prs_geom._version import __version__
from prs_geom.analysis.contact import ContactResult, analyse_contact
from prs_geom.analysis.load_solver import LoadModel
from prs_geom.analysis.loads import LoadsResult, ModelRisk, analyse_loads, build_model
from prs_geom.analysis.loads import design_pitch as _design_pitch
from prs_geom.exports.output import AtomicOutputDir
from prs_geom.exports.report import (BuildResults, ChecksResult, MeshStage, PitchLists,
                                     check_warnings, constant_pitch_section, fe_cache_warnings, gear_warnings,
                                     inspection_section, mechanism_warnings, rating_warnings, report_dict,
                                     ActuatorStage, actuator_warnings,
                                     step_files, step_warnings)
from prs_geom.harmonic.model import HarmonicDesign
from prs_geom.model.design import PRSDesign
from prs_geom.model.errors import DesignError, EnvironmentFailure, ResourceLimitError
from prs_geom.model.io import PRS_KINDS, design_hash, dumps_toml, load_design
from prs_geom.runtime.progress import ProgressFn, begin_stage, end_stage, silent, unwatch_job, watch_job

if TYPE_CHECKING:  # pragma: no cover
    import trimesh

    from prs_geom.analysis.gears import GearAnalysis
    from prs_geom.analysis.machining import MachiningSheet
    from prs_geom.analysis.rating import RatingResult
    from prs_geom.studies import ToleranceStudy
    from prs_geom.mesh.assembly import Assembly
    from prs_geom.runtime.pool import Background, Job
    from prs_geom.runtime.sidecar import Sidecar
    from prs_geom.runtime.stage_cache import StageCache, StageRecord
    from prs_geom.analysis.fe.cache import CachedInfluence
    from prs_geom.mesh.budget import Estimate

# the build's stages, its context and its worker jobs are the machinery behind build(), not API
__all__ = ["REPORT_NAME", "DESIGN_KINDS", "load_any_design", "Analysis", "LoadModels", "load_models", "analyse",
           "design_pitch", "build_meshes", "BuildOptions", "OUTPUT_GROUPS", "selected_stages", "kept_file",
           "plan_build", "build"]

#: The file name of the build report in the output folder.
REPORT_NAME = "report.json"
#: Design classes by the ``kind`` of a design file: both product lines.
DESIGN_KINDS: dict[str, type] = {**PRS_KINDS, "harmonic": HarmonicDesign}


# --------------------------------------------------------------------------- API
def load_any_design(path: str | Path) -> PRSDesign | HarmonicDesign:
    """A design file of either product line (by its ``kind``), validated.

    Examples
    --------
    >>> import prs_geom as pg
    >>> pg.save_design(pg.HarmonicDesign(), "drive.toml")
    >>> type(pg.load_design("drive.toml")).__name__
    'HarmonicDesign'
    """
    return load_design(path, DESIGN_KINDS)


@dataclass(frozen=True)
class Analysis:
    """The analysis of a design: ``contact`` (:class:`~prs_geom.analysis.contact.ContactResult`,
    e.g. ``.contact.theoretical_screw_pitch_diameter_mm``) and ``loads``
    (:class:`~prs_geom.analysis.loads.LoadsResult`, e.g. ``.loads.max_ldc``).

    Examples
    --------
    >>> import prs_geom as pg
    >>> result = pg.analyse(pg.default_design())
    >>> isinstance(result, pg.Analysis), result.design.name
    (True, 'default')
    """

    design: PRSDesign
    contact: ContactResult
    loads: LoadsResult


@dataclass(frozen=True)
class LoadModels:
    """The load model a design asks for (``loads.compliance``) and what it was made from.

    ``model`` is the one the analysis uses; with ``"fe"``, ``compare`` holds by name the
    analytic model, the FE model (``"fe"``) and its documented alternatives
    (:data:`prs_geom.analysis.fe.compliance.ALTERNATIVES`) for the model-risk study,
    ``designed_with`` the two whose equal-load lists it evaluates (analytic and FE),
    ``descriptions`` a line per model, and ``cache`` says where the influence matrices came
    from (:mod:`prs_geom.analysis.fe.cache`; ``alternative_cache`` for the sections that end
    at the engaged teeth, a separate entry)."""

    model: LoadModel
    compare: dict[str, LoadModel] | None = None
    cache: "CachedInfluence | None" = None
    alternative_cache: "CachedInfluence | None" = None
    designed_with: tuple[str, ...] = ()
    descriptions: dict[str, str] = field(default_factory=dict)

    def model_risk(self, design: PRSDesign) -> ModelRisk | None:
        """The model-risk study of ``design`` under these models
        (:func:`prs_geom.analysis.loads.model_risk`), or None for the analytic model alone."""
        if not self.compare:
            return None
        from prs_geom.analysis.loads import model_risk

        return model_risk(design, self.compare, designed_with=self.designed_with or None,
                          descriptions=self.descriptions)

    @property
    def risk_options(self) -> dict[str, Any]:
        """The keyword arguments of the model-risk study
        (:func:`prs_geom.analysis.loads.analyse_loads`)."""
        return {"compare": self.compare, "designed_with": self.designed_with or None,
                "descriptions": self.descriptions}

    @property
    def cache_report(self) -> dict[str, Any] | None:
        """Where the FE influence matrices came from, as report.json prints it inside
        ``loads.compliances.details.fe`` (None for the analytic model)."""
        if self.cache is None:
            return None
        out = self.cache.report()
        if self.alternative_cache is not None:
            out["sections_cut_at_engaged_teeth"] = self.alternative_cache.report()
        return out


def load_models(design: PRSDesign, contact: ContactResult | None = None,
                progress: ProgressFn = silent) -> LoadModels:
    """The analytic load model, or with ``loads.compliance = "fe"`` the FE one, its influence
    matrices read from the cache or computed and stored there (progress
    ``"fe matrices"``). Raises :class:`~prs_geom.model.errors.EnvironmentFailure` with the
    install command when the FE extra is missing."""
    contact = analyse_contact(design) if contact is None else contact
    analytic = build_model(design, contact)
    if design.loads.compliance != "fe":
        return LoadModels(analytic)
    from prs_geom.analysis.fe.compliance import ALTERNATIVES, MAIN_VARIANT, fe_load_model
    from prs_geom.analysis.fe.cache import cached_influence

    # the teeth's compliance is that of the constant-pitch thread: a graded design's contact
    # points move by its sub-um warps, which must not make a new cache key or new matrices
    fe_contact = analyse_contact(design.constant_pitch()) if design.graded else contact
    cached = cached_influence(design.constant_pitch(), fe_contact, progress=progress)
    fe = fe_load_model(analytic, cached.influence)
    short = cached_influence(design.constant_pitch(), fe_contact, progress=progress, extension=0,
                             label="fe matrices, sections cut at the engaged teeth")
    compare = {"analytic": analytic, "fe": fe}
    descriptions = {"analytic": "Yamamoto's diagonal tooth terms and the 1D bars (docs/theory/loads.md)",
                    "fe": MAIN_VARIANT.description}
    for v in ALTERNATIVES:
        compare[v.name] = fe_load_model(analytic, cached.influence if v.extended else short.influence, v)
        descriptions[v.name] = v.description
    return LoadModels(fe, compare, cached, short, ("analytic", "fe"), descriptions)


def analyse(design: PRSDesign, progress: ProgressFn = silent) -> Analysis:
    """Contact points, theoretical screw diameter and load distribution of ``design``
    (with the compliance model of ``design.loads.compliance``; with ``"fe"`` also the model
    risk, ``.loads.model_risk``).

    Examples
    --------
    >>> import prs_geom as pg
    >>> result = pg.analyse(pg.default_design())
    >>> round(result.contact.theoretical_screw_pitch_diameter_mm, 6)   # mm, from 24 mm nominal
    23.86787
    >>> round(result.loads.max_ldc, 4)     # worst tooth's load over the mean, constant pitch
    1.4292
    """
    contact = analyse_contact(design)
    models = load_models(design, contact, progress)
    return Analysis(design, contact, analyse_loads(design, contact, progress=progress, model=models.model,
                                                   **models.risk_options))


def design_pitch(design: PRSDesign, target: str | dict[str, Any] = "equal", name: str | None = None) -> PRSDesign:
    """A new design whose pitch lists give ``target`` load sharing at the design load:
    ``"equal"`` or ``{"nut_roller": [...], "roller_screw": [...]}`` (mean 1 each), under
    the compliance model of ``design.loads.compliance``.

    Examples
    --------
    >>> import prs_geom as pg
    >>> graded = pg.design_pitch(pg.default_design())
    >>> graded.graded, len(graded.roller.pitch_list_mm)      # one pitch per tooth gap
    (True, 19)
    >>> round(pg.analyse(graded).loads.max_ldc, 9)           # equal sharing at the design load
    1.0
    """
    return _design_pitch(design, target, name, model=load_models(design).model)


def build_meshes(design: PRSDesign, tol: float | None = None) -> dict[str, "trimesh.Trimesh"]:
    """Triangle meshes of the design, by name, as ``prs-geom build`` writes them.

    * ``screw``, ``roller``, ``nut``, ``carrier``, ``retaining_ring`` (and an actuator's
      purchased envelopes): the complete parts in their own frames, the solids of the
      per-part STL files (:mod:`prs_geom.mesh.parts`; the screw is the theoretical screw
      the analysis certifies, as ``screw.stl``).
    * ``screw_thread``, ``roller_thread``, ``nut_thread``: the thread bodies alone in the
      same frames (face A, datum A, at z = 0 of the roller and the nut).
    * every placed piece of the assembly (``roller_0`` ..., ``roller_0_gear_lo``, ...) in
      the screw frame, but for a piece named as its part (an actuator's ``locknut`` and
      ``shaft_ring``), which stays the part in its own frame.

    ``tol`` is the chord tolerance (mm; the design's by default).

    Examples
    --------
    >>> import prs_geom as pg
    >>> meshes = pg.build_meshes(pg.default_design(), tol=0.05)
    >>> all(meshes[name].is_watertight for name in ("screw", "roller", "nut"))
    True
    """
    import trimesh

    from prs_geom.analysis.contact import theoretical_screw
    from prs_geom.mesh.assembly import build_assembly

    asm = build_assembly(design, tol=tol, screw_profile=theoretical_screw(design).profile)
    out = {name: trimesh.Trimesh(part.vertices, part.faces, process=False)
           for name, part in asm.complete_parts().items()}
    out.update({f"{name}_thread": tm.to_trimesh() for name, tm in asm.parts.items()})
    for name in asm.placed:
        # a one-piece part (the locknut, the shaft ring) keeps its own frame under its name
        if name not in out:
            out[name] = asm.placed_mesh(name)
    return out


# --------------------------------------------------------------------------- context
@dataclass(frozen=True)
class BuildOptions:
    """What a build writes beyond the default set (``prs-geom build`` flags).

    Attributes
    ----------
    nominal_screw : bool
        Also export the nominal screw (``screw_nominal.stl``; ``--screw nominal``). The
        exported ``screw.stl`` is always the theoretical screw the analysis certifies.
    step : bool
        Also write ``screw.step``, ``roller.step``, ``nut.step``: B-rep solids (screw theoretical)
        (``--step``; needs the optional extra ``prs-geom[step]``; docs/step.md).
    """

    nominal_screw: bool = False
    #: also write <part>.step (B-rep solids; optional extra [step], several seconds)
    step: bool = False
    #: write only these output groups (keys of :data:`OUTPUT_GROUPS`) plus report.json; empty:
    #: every output. Only the stages they need run (``--only``).
    only: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        only = tuple(self.only)
        if any(g not in OUTPUT_GROUPS for g in only):
            raise DesignError("--only", ",".join(only), f"must be a comma list of {', '.join(OUTPUT_GROUPS)}")
        # "step" asks for the STEP files, so it implies --step
        object.__setattr__(self, "only", tuple(sorted(set(only), key=list(OUTPUT_GROUPS).index)))
        if "step" in self.only:
            object.__setattr__(self, "step", True)

    def wants(self, group: str) -> bool:
        """Whether the build writes the outputs of ``group`` (every build but an ``--only``
        without it; ``html`` reports them all)."""
        return not self.only or group in self.only or "html" in self.only


OUTPUT_GROUPS: dict[str, tuple[frozenset[str], tuple[str, ...]]] = {
    "design": (frozenset({"design"}), ("design.toml",)),
    "meshes": (frozenset({"pitch", "contact", "meshes"}), ("*.stl", "assembly.glb", "assembly.3mf")),
    "step": (frozenset({"pitch", "contact", "meshes"}), ("*.step",)),
    "sheets": (frozenset({"pitch", "contact", "manufacturing"}), ("machining*.csv", "machining.xlsx",
                                                                  "inspection.csv")),
    "drawings": (frozenset({"pitch", "contact", "manufacturing"}), ("drawing_*.dxf", "drawings.pdf",
                                                                    "profiles.dxf")),
    "plots": (frozenset({"pitch", "contact", "loads", "rating", "tolerance"}), ("*.png", "*.svg")),
    "parts_list": (frozenset({"pitch", "contact", "meshes", "mechanism", "actuator"}),
                   ("parts_list.csv", "parts_list.xlsx")),
    "html": (frozenset(), ("report.html",)),    # every stage: the page reports them all
}
"""The output groups ``--only`` selects: group -> (the stages it needs, their upstream ones
included; the files it keeps, shell patterns). report.json is always written; ``html`` runs
every stage."""


def selected_stages(only: tuple[str, ...]) -> list[tuple[str, Callable[["BuildContext"], None]]]:
    """The stages of :data:`STAGES` that the output groups ``only`` need, in run order
    (all of them for ``html`` or when ``only`` is empty)."""
    if not only or "html" in only:
        return list(STAGES)
    need = frozenset().union(*(OUTPUT_GROUPS[g][0] for g in only))
    return [(name, fn) for name, fn in STAGES if name in need]


def kept_file(name: str, only: tuple[str, ...]) -> bool:
    """Whether output file ``name`` belongs to one of the groups ``only`` (report.json
    always does)."""
    from fnmatch import fnmatchcase

    return name == REPORT_NAME or any(fnmatchcase(name, pat) for g in only for pat in OUTPUT_GROUPS[g][1])


@dataclass(frozen=True)
class _Pending:
    """A place in the report's file list kept for a background job's files."""

    #: the stage whose job writes the files
    job: str


#: what the console calls a stage's background job, where the stage name alone would mislead
_JOB_LABELS = {"meshes": "mesh checks", "manufacturing": "drawings", "loads": "load plots",
               "rating": "rating plots", "tolerance": "tolerance plots"}


def _job_label(stage: str) -> str:
    return _JOB_LABELS.get(stage, stage)


@dataclass
class BuildContext:
    """What stages share: the design, the temporary output folder and each stage's typed
    result (``results``, filled in stage order, each computed once; report.json is rendered
    from it, :func:`prs_geom.exports.report.report_dict`)."""

    design: Any
    out: Path
    progress: ProgressFn = silent
    options: BuildOptions = field(default_factory=BuildOptions)
    #: each stage's result (a new one, with the design's sizing warnings, when not given)
    results: BuildResults | None = None
    plots_svg: dict[str, str] = field(default_factory=dict)
    #: the stages whose background job was started (taken or not)
    submitted: set[str] = field(default_factory=set)
    #: the stages run or restored so far, in order
    finished: list[str] = field(default_factory=list)
    #: worker processes for the checks, drawings and plots (None: all in this process)
    background: "Background | None" = None
    #: background jobs by the stage whose result they are (``checks``, ``meshes``: the mesh
    #: checks, ``manufacturing``: the drawings, ``loads``/``rating``/``tolerance``: their plots)
    jobs: dict[str, "Job"] = field(default_factory=dict)
    #: the stages of this run (name, function): a job is started only for a stage that will run
    stages: list[tuple[str, Any]] = field(default_factory=list)
    #: time of background jobs by the stage that started them (s)
    worker_seconds: dict[str, float] = field(default_factory=dict)
    #: time the main process waited for background jobs, by the stage that waited (s)
    waited: dict[str, float] = field(default_factory=dict)
    #: the stage running now
    current_stage: str = ""
    #: the stage cache's keys and records for this build (None: every stage computes;
    #: :mod:`prs_geom.build_cache`)
    plan: "CachePlan | None" = None
    #: what each plot job drew: job -> (file names, SVG texts by plot)
    plot_outputs: dict[str, tuple[list[str], dict[str, str]]] = field(default_factory=dict)
    #: times :meth:`collect_plots` flattened the file list, and its length then
    flattened: tuple[int, int] = (0, 0)
    #: SHA-256 of the output files whose content the cache knows (restored or stored)
    known_sha256: dict[str, str] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.results is None:
            harmonic = isinstance(self.design, HarmonicDesign)
            self.results = BuildResults(self.design, kind="harmonic" if harmonic else "prs",
                                        warnings=[] if harmonic else self.design.sizing_warnings())

    def runs(self, stage: str) -> bool:
        """Whether ``stage`` is one of this run's stages."""
        return any(name == stage for name, _ in self.stages)

    @property
    def hits(self) -> dict[str, "StageRecord"]:
        """The records the cache gave, by stage: those stages are restored, not run."""
        return self.plan.hits if self.plan is not None else {}

    def computes(self, stage: str) -> bool:
        """Whether ``stage`` runs and computes its result (its record is not restored from
        the cache)."""
        return self.runs(stage) and (self.plan is None or self.plan.computes(stage))

    def submit(self, stage: str, fn: Callable[..., Any], *args: Any, progress: bool = False, plot: bool = False,
               **kwargs: Any) -> None:
        """Start ``fn(*args, **kwargs)``, the background work of ``stage``, in a worker process
        when the build has them; else it runs in this process when taken (:meth:`take`), and
        ``progress=True`` hands it this build's progress callback (a worker reports none).
        ``plot=True``: a figure, which the build's plot process draws when it has one
        (:mod:`prs_geom.runtime.sidecar`)."""
        from prs_geom.runtime.pool import Background

        bg = self.background if self.background is not None else Background(0)
        if progress and not bg.workers:
            kwargs["progress"] = self.progress
        job = self.jobs[stage] = bg.submit(fn, *args, report_progress=progress and bg.workers > 0, plot=plot,
                                           **kwargs)
        self.submitted.add(stage)
        if job.in_worker:
            watch_job(self.progress, _job_label(stage), job.poll)

    def take(self, stage: str) -> Any:
        """The result of the background work of ``stage`` (waits for it). Its time is booked
        to ``stage``; the wait is not booked to the stage running now."""
        job = self.jobs.pop(stage)
        t0 = time.perf_counter()
        value = job.result()
        waited = time.perf_counter() - t0
        if job.in_worker:   # fixed at submission, so still true once the result is taken
            unwatch_job(self.progress, _job_label(stage), job.seconds)
        self.worker_seconds[stage] = self.worker_seconds.get(stage, 0.0) + job.seconds
        self.waited[self.current_stage] = self.waited.get(self.current_stage, 0.0) + waited
        return value

    def add_plot(self, stage: str, plot: Callable[..., list[str]], *args: Any, matplotlib: bool = True) -> None:
        """Draw the figure of ``stage`` with a plot function of :mod:`prs_geom.exports.plots`
        (in a worker when there are any); its files keep their place in the report's file
        list, its SVG text goes to ``plots_svg`` when :meth:`collect_plots` runs.
        ``matplotlib=False``: a figure of the light renderer, which the plot process of a
        rebuild leaves to this process (it costs less than the pickles)."""
        from prs_geom.exports.plots import plot_detached

        self.submit(stage, plot_detached, plot, *args, plot=matplotlib)
        self.results.files.append(_Pending(stage))

    def collect_plots(self) -> None:
        """Wait for the plots still drawing; put their files and SVG texts in place. The ones
        that run in this process go first, while the workers draw theirs."""
        pending = [e.job for e in self.results.files if isinstance(e, _Pending)]
        for job in sorted(pending, key=lambda j: self.jobs[j].in_worker):
            self.plot_outputs[job] = self.take(job)
        files = []
        for entry in self.results.files:
            if isinstance(entry, _Pending):
                names, svgs = self.plot_outputs[entry.job]
                files += names
                self.plots_svg.update(svgs)
            else:
                files.append(entry)
        self.results.files[:] = files
        self.flattened = (self.flattened[0] + 1, len(files))

    def write_text(self, name: str, text: str) -> Path:
        path = self.out / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
        self.results.files.append(name)
        return path

    def add_file(self, name: str) -> Path:
        """Register a file a stage writes itself; returns its path in the output folder."""
        path = self.out / name
        path.parent.mkdir(parents=True, exist_ok=True)
        self.results.files.append(name)
        return path


# --------------------------------------------------------------------------- stages
def stage_design(ctx: BuildContext) -> None:
    """Write the resolved design back as ``design.toml``."""
    ctx.write_text("design.toml", dumps_toml(ctx.design, header=f"resolved design '{ctx.design.name}', "
                                                                f"written by prs_geom {__version__}"))


def stage_pitch(ctx: BuildContext) -> None:
    """Pitch lists of the three parts (tooth 1 at the loaded end)."""
    d = ctx.design
    ctx.results.pitch = PitchLists(screw_mm=tuple(d.pitch_list("screw")), roller_mm=tuple(d.pitch_list("roller")),
                                   nut_mm=tuple(d.pitch_list("nut")))


def stage_contact(ctx: BuildContext) -> None:
    """Analytic contact points and the theoretical screw pitch diameter (solved once)."""
    ctx.results.contact = analyse_contact(ctx.design)
    start_contact_jobs(ctx)


def start_contact_jobs(ctx: BuildContext) -> None:
    """Start what needs only the design and the contact result, in workers, for the stages
    that will compute (not restore) their results: the checks and the drawings."""
    if ctx.computes("checks") and "checks" not in ctx.submitted:
        ctx.submit("checks", checks_job, ctx.design, ctx.results.contact, progress=True)
    if ctx.computes("manufacturing") and ctx.options.wants("drawings") and "manufacturing" not in ctx.submitted:
        from prs_geom.exports.mechanism_drawing import write_all_drawings

        ctx.submit("manufacturing", write_all_drawings, ctx.design, ctx.results.contact, ctx.out, _build_date(),
                   __version__, progress=True)


def stage_gears(ctx: BuildContext) -> None:
    """The synchronising end gears: sizing, checks, phasing, running clearance (``gears``)."""
    from prs_geom.analysis.gears import analyse_gears

    ctx.results.gears = analyse_gears(ctx.design)
    if ctx.results.gears is not None:
        ctx.results.warnings += gear_warnings(ctx.results.gears)


def stage_loads(ctx: BuildContext) -> None:
    """Load distribution, equal-load pitch design, off-design and plots."""
    from prs_geom.exports.plots import plot_loads

    d = ctx.design
    models = load_models(d, ctx.results.contact, ctx.progress)
    ctx.results.loads = loads = analyse_loads(d, ctx.results.contact, progress=ctx.progress, model=models.model,
                                              **models.risk_options)
    ctx.results.fe_cache = models.cache_report
    for cache in (models.cache, models.alternative_cache):
        if cache is not None:
            ctx.results.warnings += fe_cache_warnings(cache)
    if loads.model_risk is not None:
        from prs_geom.exports.plots import plot_model_risk

        ctx.add_plot("model_risk", plot_model_risk, ctx.out, d.name, loads.model_risk)
    p = d.thread.pitch_mm
    pr, pn = np.array(loads.designed_roller_mm), np.array(loads.designed_nut_mm)
    ctx.add_plot("loads", plot_loads, ctx.out, d.name, constant_pitch_section(loads.distribution),
                 loads.designed_ldc, loads.designed_off_design, (pr - p) * 1e3, (pn - p) * 1e3, loads.designed_label)


#: Why the build has no robust pitch in its rating section.
BUILD_ROBUST_NOTE = ("not computed in the build: the robust pitch needs a load spectrum; run "
                     "'prs-geom rating DESIGN --spectrum FILE'")


def stage_rating(ctx: BuildContext) -> None:
    """Load ratings, life (catalogue and from the tooth loads of constant, equal-load and the
    design's pitch lists), limits, efficiency and stiffness (docs/theory/ratings.md): report
    section ``rating`` and the ``rating`` plot. Reuses the contact and load stages' results;
    the robust pitch is left to ``prs-geom rating --spectrum`` (a Monte Carlo study)."""
    from prs_geom.analysis.rating import analyse_rating
    from prs_geom.exports.plots import plot_rating

    d, loads = ctx.design, ctx.results.loads
    equal = (loads.equal_load.roller_mm, loads.equal_load.nut_mm)
    ctx.results.rating = r = analyse_rating(d, ctx.results.contact, loads.model, equal_lists=equal,
                                            robust_note=BUILD_ROBUST_NOTE)
    ctx.results.warnings += rating_warnings(r)
    ctx.add_plot("rating", plot_rating, ctx.out, d.name, r, matplotlib=False)


def stage_tolerance(ctx: BuildContext) -> None:
    """Monte Carlo tolerance study, only for a design with a ``[tolerances]`` section
    (docs/theory/tolerances.md): report section ``tolerance`` and the histogram/CDF plot."""
    d = ctx.design
    if d.tolerances is None:
        return
    from prs_geom.exports.plots import plot_tolerance
    from prs_geom.studies import Execution, tolerance_study

    # the build's own worker count: the study shares the build's pool (a pool of another size
    # would be resized under the build's running jobs) and its memory plan (plan_build); the
    # numbers are the same on any number of workers (prs_geom.runtime.scaleout)
    workers = ctx.background.workers if ctx.background is not None else 0
    ctx.results.tolerance = study = tolerance_study(d, contact=ctx.results.contact, model=ctx.results.loads.model,
                                            execution=Execution(workers=max(workers, 1), progress=ctx.progress))
    per_case = [(f"{f * 100:g} % load", study.stats.worst[i]) for i, f in enumerate(study.load_fractions)]
    ctx.add_plot("tolerance", plot_tolerance, ctx.out, d.name, study.worst,
                 per_case if len(per_case) > 1 else [], float(study.deterministic.max()))


def mesh_checks_job(design: PRSDesign, parts: dict[str, Any], progress: ProgressFn = silent) -> list[dict[str, Any]]:
    """``checks.meshes``: each part mesh against its analytic surface and volume
    (:func:`prs_geom.mesh.thread.mesh_report`), in the order of ``parts``."""
    from prs_geom.geometry.frames import screw_thread_length, thread_length
    from prs_geom.mesh.thread import analytic_thread_volume, mesh_report, run_out_volume

    rows = []
    lengths = {"screw": screw_thread_length(design), "roller": thread_length(design), "nut": thread_length(design)}
    for i, (name, tm) in enumerate(parts.items()):
        graded = not tm.warp.is_identity
        vol = None if graded else analytic_thread_volume(
            tm.profile, lengths[name], tm.body_radius) - tm.datum_mark.volume + sum(
            run_out_volume(tm.profile, ro) for ro in tm.run_outs)
        rows.append(mesh_report(tm, vol))
        progress("mesh checks", i + 1, len(parts))
    return rows


def stage_meshes(ctx: BuildContext) -> None:
    """Thread meshes, assembly, mesh checks (``checks.meshes``; in a worker while the meshes
    are written, taken at the checks stage) and mesh exports."""
    from prs_geom.exports.html import scene_payload
    from prs_geom.exports.meshes import export_meshes
    from prs_geom.mesh.assembly import build_assembly, build_part
    from prs_geom.runtime.memwatch import release_free_heap

    d = ctx.design
    # the screw of every export is the theoretical one (the state the analysis certifies)
    asm = build_assembly(d, progress=ctx.progress, screw_profile=ctx.results.contact.screw_profile)
    ctx.results.meshes = MeshStage(asm)
    start_mesh_checks(ctx)
    # the heap is trimmed after each step that frees large temporaries (release_free_heap):
    # this stage runs while the checks worker holds its BVHs, the build's peak
    release_free_heap()
    if ctx.runs("html"):
        # report.html's 3D view, at the display tolerance: with the meshes, whose inputs it has
        ctx.results.meshes = MeshStage(asm, scene_payload(d, screw_profile=ctx.results.contact.screw_profile))
        release_free_heap()
    asm.complete_parts()        # manifold3d unions: 0.1 GB of temporaries on the default design
    release_free_heap()
    nominal = build_part(d, "screw") if ctx.options.nominal_screw else None
    for name in export_meshes(asm, ctx.out, design_hash(d), nominal):
        ctx.results.files.append(name)
    for part in asm.complete_parts().values():
        part.edge_check()      # report.json's closed/shells, found once with the meshes they check
    if ctx.options.step:
        _write_step_files(ctx, asm)


def start_mesh_checks(ctx: BuildContext) -> None:
    """The mesh checks: started in a worker and taken by the checks stage when that stage
    computes; none when its record comes from the cache (which holds them); run here when
    the build has no checks stage (``--only meshes``) and they are not known yet."""
    parts = ctx.results.meshes.assembly.parts
    if ctx.computes("checks"):
        if "meshes" not in ctx.submitted:
            ctx.submit("meshes", mesh_checks_job, ctx.design, parts, progress=True)
    elif not ctx.runs("checks") and ctx.results.mesh_checks is None:
        ctx.results.mesh_checks = mesh_checks_job(ctx.design, parts, ctx.progress)


#: What a stage starts for later ones, run after it whether it computed or was restored.
_STARTS: dict[str, Callable[["BuildContext"], None]] = {"contact": start_contact_jobs, "meshes": start_mesh_checks}


def _bounds(part: Any) -> NDArray[np.float64]:
    """The (2, 3) min and max corners of a complete part's mesh (mm)."""
    return np.stack([part.vertices.min(axis=0), part.vertices.max(axis=0)])


def _write_step_files(ctx: BuildContext, asm: Any) -> None:
    """``<part>.step`` per made part (one file each, named like its STL: the CAD habit) and
    ``assembly.step`` (:mod:`prs_geom.exports.step_assembly`) with every part placed."""
    from prs_geom.exports.step import (MECHANISM_STEP_PARTS, complete_screw_solid, mechanism_step_solid, step_solid,
                                       write_solids)
    from prs_geom.exports.step_assembly import (ASSEMBLY_FILE, assembly_files, envelope_shapes, product_labels,
                                                write_step_assembly)
    from prs_geom.exports.step_gears import complete_nut_solid, complete_roller_solid

    d = ctx.design
    screw_profile = ctx.results.contact.screw_profile
    solids = [step_solid(d, part, screw_profile=screw_profile) for part in ("screw", "roller", "nut")]
    # the complete parts, each checked against its complete mesh (docs/step.md)
    screw, roller, nut = (asm.complete_part(part) for part in ("screw", "roller", "nut"))
    solids[0] = complete_screw_solid(d, solids[0], screw.volume_mm3, screw_profile, _bounds(screw))
    solids[1] = complete_roller_solid(d, solids[1], roller.volume_mm3, _bounds(roller))
    solids[2] = complete_nut_solid(d, solids[2], nut.volume_mm3, _bounds(nut))
    # the carrier and the ring (when the design has them) as exact B-reps
    solids += [mechanism_step_solid(d, part, asm.placed[f"{part}_lo"][0])
               for part in MECHANISM_STEP_PARTS if f"{part}_lo" in asm.placed]
    writes = [(s.part, write_solids([s], ctx.out / f"{s.part}.step")) for s in solids]
    ctx.results.step = tuple(writes)
    ctx.results.files += step_files(ctx.results.step)
    ctx.results.warnings += step_warnings(ctx.results.step)
    shapes = {**{s.part: s.shape for s in solids if s.valid}, **envelope_shapes(d)}
    thread_bodies = tuple(s.part for s in solids[:3] if not s.complete and s.part in asm.complete_parts()
                          and len(asm.complete_parts()[s.part].pieces) > 1)
    ctx.results.step_assembly = write_step_assembly(asm.complete_parts(), shapes, ctx.out / ASSEMBLY_FILE, d.name,
                                                    product_labels(d), thread_bodies)
    ctx.results.files += assembly_files(ctx.results.step_assembly)


def checks_job(design: PRSDesign, contact: ContactResult, progress: ProgressFn = silent) -> ChecksResult:
    """FCL verification of the contacts and the interference check (both screws), with the
    theoretical screw of the contact stage. Needs
    only the design and the contact result, so a build starts it in a worker right after
    the contact stage."""
    from prs_geom.checks.fcl import verify_contacts
    from prs_geom.checks.interference import interference_checks

    screw = contact.screw_profile
    fcl_section = verify_contacts(design, screw_profile=screw, designed_gaps=contact.tooth_gaps)
    progress("fcl verification", 1, 1)
    return ChecksResult(fcl=fcl_section, interference=interference_checks(design, screw, progress=progress))


def stage_checks(ctx: BuildContext) -> None:
    """The mesh checks started by the meshes stage (run here when that stage's record came
    from the cache), then the checks of :func:`checks_job` started after the contact stage."""
    if "meshes" in ctx.jobs:
        ctx.results.mesh_checks = ctx.take("meshes")
    elif ctx.results.mesh_checks is None:
        ctx.results.mesh_checks = mesh_checks_job(ctx.design, ctx.results.meshes.assembly.parts, ctx.progress)
    ctx.results.checks = checks = ctx.take("checks")
    ctx.results.warnings += check_warnings(ctx.results.mesh_checks, checks)


def _build_date() -> str:
    """Date a build prints (drawing title blocks, report.html): SOURCE_DATE_EPOCH when set
    (reproducible builds, the goldens), else today (UTC)."""
    import os
    from datetime import datetime, timezone

    epoch = os.environ.get("SOURCE_DATE_EPOCH")
    when = datetime.fromtimestamp(int(epoch), timezone.utc) if epoch else datetime.now(timezone.utc)
    return when.date().isoformat()


def stage_manufacturing(ctx: BuildContext) -> None:
    """Inspection values, machining sheets (CSV per part, one XLSX), the DXF profiles and the
    per-part drawings (DXF and one PDF)."""
    from prs_geom.analysis.machining import machining_sheets
    from prs_geom.exports.dxf import write_dxf
    from prs_geom.exports.sheets import sheet_csv, write_xlsx

    from prs_geom.analysis.inspection import inspection

    ctx.results.inspection = inspection(ctx.design, ctx.results.contact)
    insp = inspection_section(ctx.results.inspection)
    from prs_geom.exports.sheets import inspection_csv

    ctx.write_text("inspection.csv", inspection_csv(insp))
    ctx.results.machining = sheets = machining_sheets(ctx.design, ctx.results.contact, insp)
    for part, sh in sheets.items():
        ctx.write_text(f"machining_{part}.csv", sheet_csv(sh))
    write_xlsx(sheets, ctx.add_file("machining.xlsx"), __version__, _build_date())
    extra = {"theoretical screw pitch dia. (grind to)":
             f"{ctx.results.contact.theoretical_screw_pitch_diameter_mm:.6f} mm"}
    from prs_geom.exports.drawing import part_profiles

    write_dxf(ctx.design, ctx.add_file("profiles.dxf"), extra, part_profiles(ctx.design, ctx.results.contact),
              _build_date())
    if "manufacturing" in ctx.jobs:     # the drawings, started after the contact stage when wanted
        ctx.results.files += ctx.take("manufacturing")


def stage_mechanism(ctx: BuildContext) -> None:
    """Carriers, journals, retaining rings (placed by the meshes stage): sizes, fits, the
    journal clearances on the meshes, the axial stack-up (``mechanism``); the kinematics of
    the running mechanism (``kinematics``); and the parts list (``parts_list``,
    parts_list.csv and parts_list.xlsx)."""
    from prs_geom.exports.bom import parts_list, parts_list_csv, write_parts_list_xlsx
    from prs_geom.mesh.volumes import part_volumes
    from prs_geom.geometry.mechanism import layout

    d = ctx.design
    asm = ctx.results.meshes.assembly
    lay = layout(d)
    if lay is not None:
        from prs_geom.checks.mechanism import check_mechanism

        ctx.results.mechanism = check_mechanism(asm, lay, lay.ring.designation)
        ctx.results.warnings += mechanism_warnings(ctx.results.mechanism)
    from prs_geom.analysis.kinematics import check_kinematic_sizing, kinematics

    try:
        check_kinematic_sizing(d)
    except ValueError:
        pass                  # off the standard nut sizing: no ideal kinematics (and no animation)
    else:
        ctx.results.kinematics = kinematics(d, ctx.results.contact)
    rows = parts_list(d, part_volumes(asm))
    ctx.results.parts_list = rows
    ctx.write_text("parts_list.csv", parts_list_csv(rows, d.name))
    write_parts_list_xlsx(rows, ctx.add_file("parts_list.xlsx"), d.name, __version__, _build_date())


def stage_actuator(ctx: BuildContext) -> None:
    """The actuator's screw ends, supports and nut flange at the two stroke ends
    (``actuator``): a stage of its own because its flange-bolt check compares the bolts'
    proof loads with the design load, which nothing else of the mechanism reads."""
    from prs_geom.geometry.actuator import actuator_layout, stroke_end_checks

    d = ctx.design
    act = actuator_layout(d)
    if act is not None:
        # the engagement is the same all along the stroke: only the ends are checked there
        ctx.results.actuator = ActuatorStage(act, stroke_end_checks(d, act))
        ctx.results.warnings += actuator_warnings(ctx.results.actuator)


def stage_html(ctx: BuildContext) -> None:
    """The self-contained HTML report, from the stage results."""
    from prs_geom.exports.html import write_html

    ctx.collect_plots()

    write_html(ctx.add_file("report.html"), ctx.results, ctx.plots_svg, _build_date(), __version__)


#: Stages in run order: (report name, function).
STAGES: list[tuple[str, Callable[[BuildContext], None]]] = [
    ("design", stage_design),
    ("pitch", stage_pitch),
    ("contact", stage_contact),
    ("gears", stage_gears),
    ("loads", stage_loads),
    ("rating", stage_rating),
    ("tolerance", stage_tolerance),
    ("meshes", stage_meshes),
    ("mechanism", stage_mechanism),
    ("actuator", stage_actuator),
    ("checks", stage_checks),
    ("manufacturing", stage_manufacturing),
    ("html", stage_html),
]


#: BuildResults fields no stage owns: the design, the product line, and those a record keeps
#: in its own form (warnings, files) or not at all (timings)
_SHARED_FIELDS = frozenset({"design", "kind", "warnings", "files", "timings_s"})


@dataclass
class _StageMark:
    """What the build results held when a stage began, to tell what the stage added."""

    values: dict[str, Any]
    warnings: int
    files: int
    flattened: int

    @classmethod
    def of(cls, ctx: BuildContext) -> "_StageMark":
        values = {f: getattr(ctx.results, f) for f in _result_fields()}
        return cls(values, len(ctx.results.warnings), len(ctx.results.files), ctx.flattened[0])

    def added(self, ctx: BuildContext) -> tuple[dict[str, Any], list[str], list[Any]]:
        """The result fields the stage set, the warnings and the file entries it added
        (plot placeholders included)."""
        res = ctx.results
        changed = {f: getattr(res, f) for f in _result_fields() if getattr(res, f) is not self.values[f]}
        start = ctx.flattened[1] if ctx.flattened[0] != self.flattened else self.files
        return changed, list(res.warnings[self.warnings:]), list(res.files[start:])


def _result_fields() -> list[str]:
    import dataclasses

    return [f.name for f in dataclasses.fields(BuildResults) if f.name not in _SHARED_FIELDS]


@dataclass(frozen=True)
class CachePlan:
    """A build's stage cache, the key of each of its stages and the records found for them."""

    cache: "StageCache"
    #: stage -> (key, description), for the build's stages in run order
    keys: dict[str, tuple[str, str]]
    #: stage -> the record the cache holds under its key
    hits: dict[str, "StageRecord"]
    #: the stages whose stored record is still to be read (:meth:`defer`)
    pending: set[str] = field(default_factory=set)
    #: the stages whose record was looked for
    looked: set[str] = field(default_factory=set)

    @classmethod
    def keyed(cls, cache: "StageCache", design: PRSDesign, stages: list[str], options: BuildOptions) -> "CachePlan":
        """The plan's keys, no record read yet (each is read by :meth:`take`)."""
        from prs_geom.build_cache import stage_keys
        from prs_geom.runtime.stage_cache import source_fingerprint

        return cls(cache, stage_keys(design, stages, options, _build_date(), source_fingerprint()), {})

    def stored(self, stage: str) -> bool:
        """Whether the cache has a record under the key of ``stage`` (not yet read, so not
        yet known to be sound); never while reads are disabled (``--no-cache``)."""
        from prs_geom.runtime.cache import reads_enabled

        return stage in self.keys and reads_enabled() and \
            self.cache.store.path(stage, self.keys[stage][0]).is_file()

    def defer(self) -> None:
        """Read each stored record only when its stage comes (:meth:`take`): until then the
        plan counts it as a hit. A build reads the records of a rebuild's meshes and checks
        (0.2 s) while its plot process draws the new load's figures, not before."""
        self.pending.update(s for s in self.keys if self.stored(s))

    def take(self, stage: str, design: PRSDesign) -> "StageRecord | None":
        """The record of ``stage``: read now if it has not been, a hit only when sound."""
        if stage in self.keys and stage not in self.looked:
            self.pending.discard(stage)
            self.looked.add(stage)
            record, _ = self.cache.read(stage, *self.keys[stage], design)
            if record is not None:
                self.hits[stage] = record
        return self.hits.get(stage)

    def computes(self, stage: str) -> bool:
        """Whether ``stage`` is one of the build's and its record is not in the cache (as far
        as known: a deferred record counts as a hit until read)."""
        return stage in self.keys and stage not in self.hits and stage not in self.pending


def _restore(ctx: BuildContext, name: str) -> None:
    """Put the cached record of stage ``name`` in place: results, warnings, files, plots;
    then start what the stage starts for later ones."""
    record = ctx.hits[name]
    for attr, value in record.results.items():
        setattr(ctx.results, attr, value)
    ctx.results.warnings += list(record.warnings)
    for file_name, sha in record.files:
        shutil.copyfile(ctx.plan.cache.blob(sha), ctx.add_file(file_name))
        ctx.known_sha256[file_name] = sha
    ctx.plots_svg.update(record.svgs)
    start = _STARTS.get(name)
    if start is not None:
        start(ctx)


def _store_records(ctx: BuildContext, added: dict[str, tuple[dict[str, Any], list[str], list[Any]]]) -> None:
    """Write the record of every stage this build computed (not one whose results the
    record format does not carry: that stage runs every time)."""
    from prs_geom.runtime.cache import file_sha256
    from prs_geom.runtime.stage_cache import StageRecord, Uncacheable

    for name, (results, warnings, entries) in added.items():
        files, svgs = [], {}
        for entry in entries:
            if isinstance(entry, _Pending):
                names, drawn = ctx.plot_outputs[entry.job]
                files += names
                svgs.update(drawn)
            else:
                files.append(entry)
        for f in files:
            ctx.known_sha256[f] = file_sha256(ctx.out / f)
        record = StageRecord(results, tuple(warnings), tuple((f, ctx.known_sha256[f]) for f in files), svgs)
        try:
            ctx.plan.cache.write(name, *ctx.plan.keys[name], record, {f: ctx.out / f for f in files}, ctx.design)
        except Uncacheable:
            pass


def _needs_workers(plan: CachePlan, design: PRSDesign) -> bool:
    """Whether the stages left to compute have background work that pays for worker
    processes (the checks, the drawings, a tolerance study): a build that restores those
    from the cache runs in one process."""
    return plan.computes("checks") or plan.computes("manufacturing") or \
        (plan.computes("tolerance") and design.tolerances is not None)


def _start_late(ctx: BuildContext) -> None:
    """A deferred record that proved unsound when its stage came (:meth:`CachePlan.defer`):
    the stage computes after all, so start now what the stages before it skipped for it
    (:data:`_STARTS`; each starts only what was not started yet). Without workers (the plan
    expected none) the jobs run when taken."""
    for stage in ctx.finished:
        start = _STARTS.get(stage)
        if start is not None:
            start(ctx)


def _stage_label(ctx: BuildContext, name: str) -> str:
    return f"{name} (reused from the cache)" if name in ctx.hits else name


def run_stages(design, out: Path, progress: ProgressFn = silent,
               stages: list[tuple[str, Callable[[BuildContext], None]]] | None = None,
               options: BuildOptions | None = None, workers: int | None = None,
               plan: CachePlan | None = None, sidecar: "Sidecar | None" = None) -> BuildContext:
    """Run ``stages`` (:data:`STAGES` by default) on a new :class:`BuildContext`; the checks,
    drawings and plots go to worker processes when ``workers`` allows
    (:mod:`prs_geom.runtime.pool`; None: ``$PRS_GEOM_WORKERS`` or the default).

    ``timings_s`` gives each stage's own work: its wall time in the main process, less the
    time it waited for background jobs, plus the time of the jobs it started (the checks,
    the drawings of ``manufacturing``, the plots of ``loads``, ``rating``, ``tolerance``),
    wherever they ran. With workers their sum exceeds the build's wall time.

    ``plan`` (a planetary roller screw design only; :meth:`CachePlan.keyed` for ``stages``): a
    stage whose key (:mod:`prs_geom.build_cache`) the cache holds is restored from its
    record instead of run (``ctx.hits``), and every stage that ran stores its record at the
    end. ``sidecar``: the plot process that :func:`_prepare` started for a rebuild; it draws
    the figures and is closed (killed and reaped) here when the stages end, whether they
    succeed or fail.
    """
    from prs_geom.runtime.memwatch import release_free_heap
    from prs_geom.runtime.pool import Background, build_threads
    from prs_geom.runtime.sidecar import shared_pool

    stages = STAGES if stages is None else stages
    ctx = BuildContext(design=design, out=out, progress=progress, options=options or BuildOptions(),
                       stages=list(stages), plan=plan)
    if plan is not None and not _needs_workers(plan, design):
        workers = 0     # what is left (a few plots) is done before worker processes would start
    # processes of the build's own (no resource trackers, no joblib), unless a tolerance study
    # runs in the build: it shares loky's pool with the build's jobs (stage_tolerance)
    own = not (ctx.computes("tolerance") and getattr(design, "tolerances", None) is not None)
    # BLAS on one thread, as in the workers: the same numbers on any machine (runtime.pool)
    with build_threads(), Background(workers, sidecar=sidecar, processes=shared_pool if own else None) as background:
        ctx.background = background
        added = {}
        for name, fn in stages:
            ctx.current_stage = name
            t0 = time.perf_counter()
            if plan is not None:
                predicted = not plan.computes(name)
                plan.take(name, design)
                if predicted and name not in ctx.hits:
                    _start_late(ctx)
            begin_stage(progress, _stage_label(ctx, name))
            if name in ctx.hits:
                _restore(ctx, name)
            else:
                mark = _StageMark.of(ctx)
                fn(ctx)
                added[name] = mark.added(ctx)
                release_free_heap()
            ctx.finished.append(name)
            ctx.results.timings_s[name] = time.perf_counter() - t0
            end_stage(progress, _stage_label(ctx, name))
        ctx.current_stage = "end"
        ctx.collect_plots()
        for key in list(ctx.jobs):  # a job no stage took (a partial stage list)
            ctx.take(key)
        if plan is not None:
            _store_records(ctx, added)
    timings = ctx.results.timings_s
    for name in timings:
        timings[name] += ctx.worker_seconds.get(name, 0.0) - ctx.waited.get(name, 0.0)
    return ctx


def harmonic_stage(ctx: BuildContext) -> None:
    """Ratio table and plot, DXF at the drawing positions, STL meshes (harmonic designs)."""
    from prs_geom.exports.meshes import stl_header, write_stl
    from prs_geom.harmonic.assembly import circular_spline_arc_bound
    from prs_geom.harmonic.exports import (circular_spline_mesh, circular_spline_profile, flexspline_mesh,
                                           flexspline_profile, plot_drive, plot_ratio, ratio_table_csv,
                                           revolve_deviation,
                                           write_dxf)
    from prs_geom.harmonic.model import harmonic_report, ratio_table, strength_warnings

    d = ctx.design
    ctx.results.harmonic = harmonic_report(d)
    ctx.results.warnings += strength_warnings(d)
    ctx.write_text("ratio_table.csv", ratio_table_csv(ratio_table(d)))
    ctx.results.files += plot_ratio(d, ctx.out)
    ctx.results.files += plot_drive(d, ctx.out)
    write_dxf(d, ctx.add_file("axial_sections.dxf"))
    rows = []
    tol = d.mesh.chord_tolerance_mm
    for name, mesh, prof, arc_bound in (
            ("circular_spline", circular_spline_mesh(d), circular_spline_profile(d), circular_spline_arc_bound(d, tol)),
            ("flexspline", flexspline_mesh(d), flexspline_profile(d), 0.5 * tol)):
        write_stl(mesh, ctx.add_file(f"{name}.stl"), stl_header(name, design_hash(d)))
        rev = revolve_deviation(mesh, prof)
        dev = rev + arc_bound
        rows.append({"part": name, "triangles": int(len(mesh.faces)), "watertight": bool(mesh.is_watertight),
                     "volume_mm3": float(mesh.volume), "chord_tolerance_mm": tol,
                     "revolution_deviation_mm": rev, "arc_chord_bound_mm": arc_bound,
                     "max_deviation_mm": dev,
                     "warnings": [f"measured deviation {dev:.3g} mm exceeds the chord tolerance {tol:g} mm"]
                     if dev > tol else []})
    ctx.results.harmonic_meshes = rows
    ctx.results.warnings += check_warnings(rows)
    from prs_geom.harmonic.exports import place_harmonic, write_harmonic_html

    # the placed assembly (wave generator, deformed flexspline), GLB and 3MF, then report.html
    placed = place_harmonic(d, ctx.out)
    ctx.results.harmonic_assembly = placed.assembly
    ctx.results.harmonic_assembly_checks = placed.checks
    ctx.results.warnings += list(placed.warnings)
    ctx.results.files += list(placed.files)
    ctx.results.files.append(write_harmonic_html(d, ctx.out, report_dict(ctx.results), placed, _build_date(),
                                                 __version__))


HARMONIC_STAGES: list[tuple[str, Callable[[BuildContext], None]]] = [
    ("design", stage_design),
    ("harmonic", harmonic_stage),
]


def _environment_failure(exc: OSError, atomic: AtomicOutputDir) -> EnvironmentFailure:
    """One line naming the path (as the user will know it, not the temporary folder) and
    the operating system's reason."""
    path = str(exc.filename) if exc.filename is not None else str(atomic.target)
    if atomic.tmp is not None:
        path = path.replace(str(atomic.tmp), str(atomic.target))
    return EnvironmentFailure(f"cannot write {path}: {exc.strerror or exc} (nothing was written; "
                              f"{atomic.given} is as it was)")


def plan_build(design: PRSDesign, memory_budget: int | None = None) -> "tuple[int, Estimate]":
    """Worker processes and the memory estimate of building ``design``: the one estimate
    that ``build`` applies and ``validate`` prints.

    The default worker count (:func:`prs_geom.runtime.pool.default_workers`), none for a
    design checked in axial windows, and none when the design fits ``memory_budget``
    (bytes; None: the default budget) only serially, because the workers' peaks add to the
    main process's. Raises :class:`~prs_geom.model.errors.ResourceLimitError` when it fits
    neither way.
    """
    from prs_geom.runtime.pool import default_workers
    from prs_geom.mesh.budget import check_windows, guard

    workers = default_workers()
    if check_windows(design) is not None:
        # a long design's check runs window by window to bound memory; beside the export
        # meshing in a worker its peak would add to the main process's again
        workers = 0
    try:
        return workers, guard(design, memory_budget, workers=workers)
    except ResourceLimitError:
        if not workers:
            raise
        # a design too large for parallel peaks runs serially (one peak at a time) when it
        # fits so, and is refused only when not
        return 0, guard(design, memory_budget, workers=0)


def _keep_only(ctx: BuildContext, tmp: Path, only: tuple[str, ...]) -> None:
    """Remove from the temporary output folder and the report's file list every file the
    stages wrote that is not in the groups ``only`` (a stage writes whole sets: the
    manufacturing stage its sheets and the profiles DXF together)."""
    kept = []
    for name in ctx.results.files:
        if kept_file(name, only):
            kept.append(name)
        elif (tmp / name).is_file():
            (tmp / name).unlink()
    ctx.results.files[:] = kept


def _stage_cache() -> "StageCache | None":
    """The stage cache, or None when ``$PRS_GEOM_STAGE_CACHE`` turns it off."""
    from prs_geom.runtime.stage_cache import StageCache, enabled

    return StageCache() if enabled() else None


def _build_into(atomic: AtomicOutputDir, ctx: BuildContext, only: tuple[str, ...]) -> dict[str, Any]:
    """After the stages: what the manifest records of the cache, the ``--only`` selection,
    report.json; returns the report dict."""
    atomic.extra["design_sha256"] = design_hash(ctx.design)     # tells a rebuild of the same design early (cli)
    if ctx.hits:
        atomic.extra["reused_from_cache"] = list(ctx.hits)
    atomic.known_sha256.update(ctx.known_sha256)
    ctx.results.files.append(REPORT_NAME)
    if only:
        _keep_only(ctx, ctx.out, only)
    report = report_dict(ctx.results)
    if only:
        # the stages that did not run have no section; "only" says why
        report = {k: v for k, v in report.items() if v is not None}
        report["only"] = list(only)
    (ctx.out / REPORT_NAME).write_text(json.dumps(report, indent=2) + "\n", encoding="utf-8")
    return report


def _prepare(design: PRSDesign, stages: list[str], options: BuildOptions, memory_budget: int | None,
             cache: bool | None, started: "Sidecar | None" = None) -> tuple[int, CachePlan | None, "Sidecar | None"]:
    """Before a planetary roller screw build: the refusals that need no work (tables, fits,
    stack-up, the optional STEP extra), the stage cache's records, the worker count
    (:func:`plan_build`, with its memory estimate; none when the meshes and the checks come
    from the cache) and, for a rebuild that has only plots left for workers, its plot
    process (:mod:`prs_geom.runtime.sidecar`): ``started`` when the caller started one
    early, else a new one, before the records are read. A ``started`` process it does not
    return is the caller's to close."""
    from prs_geom.geometry.actuator import actuator_layout
    from prs_geom.geometry.mechanism import check_layout

    check_layout(design)   # the standard tables, fits and stack-up: refused now, not after the meshing
    actuator_layout(design)
    if options.step:
        from prs_geom.exports.step import require_ocp

        require_ocp()   # a missing extra is known now, not after the meshing
    from prs_geom.runtime.cache import reads_disabled
    from prs_geom.runtime.pool import default_workers

    stage_cache = _stage_cache()
    if stage_cache is None:
        return plan_build(design, memory_budget)[0], None, None
    sidecar = None
    with reads_disabled() if cache is False else contextlib.nullcontext():
        plan = CachePlan.keyed(stage_cache, design, stages, options)
        plan.defer()    # no record is stored while reads are disabled: every stage computes
    restored = not plan.computes("meshes") and not _needs_workers(plan, design)
    if restored and any(plan.computes(s) for s in PLOT_STAGES) and default_workers() > 0:
        # only figures are left for workers: a plot process of its own pays, never with PRS_GEOM_WORKERS=0
        from prs_geom.exports.plots import warm_up
        from prs_geom.runtime.sidecar import Sidecar

        sidecar = started if started is not None else Sidecar(warm_up)
    if restored:
        return 0, plan, sidecar     # the meshes and the checks come from the cache: nothing to fit in memory
    return plan_build(design, memory_budget)[0], plan, None


#: The stages that draw figures (:meth:`BuildContext.add_plot`).
PLOT_STAGES = ("loads", "rating", "tolerance")


def build(design: PRSDesign | HarmonicDesign, out_dir: str | Path, progress: ProgressFn = silent,
          memory_budget: int | None = None, options: BuildOptions | None = None, *, force: bool = False,
          source: str | Path | None = None, cache: bool | None = None,
          plot_process: "Sidecar | None" = None) -> dict[str, Any]:
    """Run every stage and write the exports and ``report.json`` to ``out_dir``: what
    ``prs-geom build`` does.

    ``out_dir`` must be a new path, an empty folder or an earlier prs-geom output folder
    (:mod:`prs_geom.exports.output`; anything else raises
    :class:`~prs_geom.model.errors.OutputRefused` before any work). The job is refused up
    front when its estimated memory exceeds ``memory_budget`` (bytes; default a share of the
    available memory, :mod:`prs_geom.mesh.budget`); a job that fits the budget only without
    worker processes runs without them. ``options``: :class:`BuildOptions`. Written atomically: if any stage fails,
    ``out_dir`` keeps its previous content. ``force`` replaces files of an earlier output
    that were edited since prs-geom wrote them (refused otherwise); ``source``, the design
    file the design was read from: when it lies inside ``out_dir`` it is kept byte for
    byte. ``options.only``: write only those output groups (:data:`OUTPUT_GROUPS`) and
    report.json, running only the stages they need; the folder is still replaced whole and its
    manifest records ``only``. ``cache``: None or True reuse the records of stages whose
    inputs are unchanged since an earlier build and store this build's
    (:mod:`prs_geom.build_cache`, docs/cache.md); False (``--no-cache``) computes every
    stage and the FE matrices afresh and stores them again. ``$PRS_GEOM_STAGE_CACHE=0``
    turns the stage cache off (the test suite's setting). The outputs are the same every way.
    ``plot_process``: a :class:`~prs_geom.runtime.sidecar.Sidecar` the caller started early
    (the command line does, before it imports this module, when the output folder holds a
    build of the same design): the build draws its figures there when its stage records leave
    it nothing else for workers, and closes it either way. Returns the report dict.

    Examples
    --------
    >>> import prs_geom as pg
    >>> report = pg.build(pg.default_design(), "exports/default")
    >>> report["loads"]["max_ldc"] == pg.analyse(pg.default_design()).loads.max_ldc
    True
    >>> sorted(f for f in report["files"] if f.endswith(".stl"))[:3]
    ['assembly.stl', 'carrier.stl', 'nut.stl']
    """
    harmonic = isinstance(design, HarmonicDesign)
    atomic = AtomicOutputDir(out_dir, {"design": design.name}, force=force, source=source)
    only = options.only if options is not None else ()
    stages = HARMONIC_STAGES if harmonic else (selected_stages(only) if only else STAGES)
    sidecar = None
    try:
        if harmonic:
            return _build(design, atomic, stages, progress, memory_budget, options, only, cache, None, None, None)
        workers, cache_plan, sidecar = _prepare(design, [name for name, _ in stages], options or BuildOptions(),
                                                memory_budget, cache, plot_process)
        return _build(design, atomic, stages, progress, memory_budget, options, only, cache, workers, cache_plan,
                      sidecar)
    finally:
        for process in (sidecar, plot_process):     # the one not used; the used one if run_stages did not run
            if process is not None:
                process.close()


def _build(design: PRSDesign | HarmonicDesign, atomic: AtomicOutputDir, stages: Any, progress: ProgressFn,
           memory_budget: int | None, options: BuildOptions | None, only: tuple[str, ...], cache: bool | None,
           workers: int | None, cache_plan: CachePlan | None, sidecar: "Sidecar | None") -> dict[str, Any]:
    """:func:`build` once the job is prepared: the build under its memory watch, into the
    atomic output folder."""
    harmonic = isinstance(design, HarmonicDesign)
    from prs_geom.mesh.budget import BASE_BYTES, default_budget_bytes
    from prs_geom.runtime.memwatch import MemoryWatch

    # the budget holds while the build runs, too (prs_geom.runtime.memwatch): exit 3, nothing written
    watch = MemoryWatch(default_budget_bytes() if memory_budget is None else memory_budget,
                        f"the build of {design.name}", base_bytes=BASE_BYTES)
    if only and harmonic:
        raise DesignError("--only", ",".join(only), "applies to planetary roller screw builds, not to a harmonic drive")
    if only:
        atomic.extra["only"] = list(only)
    from prs_geom.runtime.cache import reads_disabled

    try:
        with watch, atomic as tmp, (reads_disabled() if cache is False else contextlib.nullcontext()):
            report = _build_into(atomic, run_stages(design, tmp, progress, stages, options, workers=workers,
                                                    plan=cache_plan, sidecar=sidecar), only)
    except ResourceLimitError:
        raise
    except OSError as exc:
        if watch.breached:
            raise watch.error() from None
        raise _environment_failure(exc, atomic) from exc
    except BaseException:
        if watch.breached:   # a worker killed for the budget, met as a broken pool
            raise watch.error() from None
        raise
    return report
