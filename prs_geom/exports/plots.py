"""Plots of the load distribution and pitch design (PNG and SVG), matplotlib Agg backend, and
of the ratings (a light renderer of its own, :func:`plot_rating`).

Exporter: takes the numbers of the loads stage (:class:`~prs_geom.analysis.loads.LoadsResult`)
and of the rating stage, writes files and hands the SVG text on (the HTML report shows it
inline).

matplotlib is imported on first use, not with this module (it costs about 1 s): the rating
figure needs none of it but a tick locator and a font file. The figures are
:class:`matplotlib.figure.Figure` objects made without pyplot (no figure manager to close);
``plt`` is still offered, lazily, for callers that draw with pyplot (the harmonic report).
"""
from __future__ import annotations

import functools
import html
import io
import math
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable

import numpy as np

__all__ = ["save_figure", "plot_detached", "warm_up", "plot_loads", "plot_model_risk", "plot_tolerance", "RATING_LABELS",
           "plot_rating"]

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

    from prs_geom.analysis.loads import ModelRisk
    from prs_geom.analysis.rating import RatingResult


@functools.cache
def _matplotlib() -> Any:
    """matplotlib, imported and set up once: the Agg backend (headless, for pyplot users) and
    a fixed SVG hash salt, so that the same figure gives the same SVG element ids, i.e. the
    same file bytes."""
    import matplotlib

    matplotlib.use("Agg")
    matplotlib.rcParams["svg.hashsalt"] = "prs-geom"
    return matplotlib


def warm_up() -> None:
    """matplotlib imported and set up as for the build's figures, its fonts loaded by a
    throwaway figure drawn to memory in PNG and SVG: the warm-up of a rebuild's plot process
    (:mod:`prs_geom.runtime.sidecar`), so that its first figure costs what the later ones do."""
    fig, ax = _figure(figsize=(2, 1))
    ax.plot([0, 1], [0, 1], "o-", label="x")
    ax.set_title("warm")
    ax.legend()
    for fmt in ("png", "svg"):
        fig.savefig(io.BytesIO(), format=fmt, dpi=130, bbox_inches="tight")


def __getattr__(name: str) -> Any:
    """``plt`` (matplotlib.pyplot on the Agg backend), imported when first asked for."""
    if name == "plt":
        _matplotlib()
        import matplotlib.pyplot as plt

        return plt
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def _figure(nrows: int = 1, ncols: int = 1, *, figsize: tuple[float, float] | None = None,
            **kw: Any) -> tuple[Figure, Any]:
    """A figure and its axes as ``pyplot.subplots(nrows, ncols, figsize=..., **kw)`` makes
    them, without pyplot: the same rcParams defaults and layout, so the same file bytes
    (``tests/test_plots.py``), and no figure manager to register and close."""
    _matplotlib()
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize)
    return fig, fig.subplots(nrows, ncols, **kw)


def save_figure(fig: Figure, out: Path, stem: str, svgs: dict[str, str] | None = None,
                tight: bool = True) -> list[str]:
    """Save ``fig`` as ``stem.png`` and ``stem.svg`` (no timestamp in the SVG) and close it;
    the SVG text also goes into ``svgs[stem]`` when a dict is given. ``tight=False`` keeps the
    figure's own layout and saves one layout pass per file (for figures laid out by hand).

    Parameters
    ----------
    fig
        A matplotlib figure, made by :func:`_figure` or by pyplot (then it is closed here).
    out
        Output folder.
    stem
        File name without suffix.
    svgs
        Receives the SVG text under ``stem`` when given.
    tight
        ``bbox_inches="tight"`` for both files.

    Returns
    -------
    list of str
        The two file names written.
    """
    _matplotlib()
    bbox = "tight" if tight else None
    fig.savefig(out / f"{stem}.png", dpi=130, bbox_inches=bbox)
    buf = io.BytesIO()
    fig.savefig(buf, format="svg", dpi=130, bbox_inches=bbox, metadata={"Date": None})
    (out / f"{stem}.svg").write_bytes(buf.getvalue())
    if svgs is not None:
        svgs[stem] = buf.getvalue().decode("utf-8")
    # a pyplot figure stays registered (and alive) until closed; a figure made without pyplot
    # has no manager, and when pyplot was never imported no figure can be one of its own
    plt = sys.modules.get("matplotlib.pyplot")
    if plt is not None and fig.canvas.manager is not None:
        plt.close(fig)
    return [f"{stem}.png", f"{stem}.svg"]


def plot_detached(plot: Callable[..., list[str]], *args: Any, **kwargs: Any) -> tuple[list[str], dict[str, str]]:
    """Run one of this module's plot functions and return what it writes, ``(file names,
    {stem: SVG text})``, instead of filling the caller's ``svgs`` dict.

    For a worker process (``ProcessPoolExecutor.submit(plot_detached, plot_loads, out, ...)``):
    the function and its arguments (paths, numbers, dicts, arrays) pickle, the files go
    straight into ``out`` and the SVG texts come back with the result. The worker sets up
    matplotlib as this process does (:func:`_matplotlib`), so the bytes are the same.

    Parameters
    ----------
    plot
        :func:`plot_loads`, :func:`plot_tolerance` or :func:`plot_rating`.
    *args, **kwargs
        Its arguments but ``svgs``.

    Returns
    -------
    tuple of (list of str, dict of str to str)
        The file names written and the SVG texts by stem.
    """
    svgs: dict[str, str] = {}
    files = plot(*args, svgs=svgs, **kwargs)
    return files, svgs


def _per_side(draw, subtitle: str, ylabel: str, title: str) -> Figure:
    """Two panels, nut-roller and roller-screw, sharing the coefficient axis; ``draw(ax, key)``
    plots the curves of one side (key: "ldc_nut_roller" or "ldc_roller_screw")."""
    fig, axes = _figure(1, 2, figsize=(10, 4), sharey=True)
    for ax, key, side in ((axes[0], "ldc_nut_roller", "nut-roller"), (axes[1], "ldc_roller_screw", "roller-screw")):
        draw(ax, key)
        ax.axhline(1.0, color="0.6", lw=0.8)
        ax.set_title(f"{side}{subtitle}")
        ax.set_xlabel("tooth (1 = loaded end)")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel(ylabel)
    axes[0].legend()
    fig.suptitle(title)
    return fig


def plot_loads(out: Path, name: str, const: dict[str, Any], designed: dict[str, Any],
               off: list[dict[str, Any]], roller_corr_um: np.ndarray, nut_corr_um: np.ndarray,
               designed_label: str, svgs: dict[str, str] | None = None) -> list[str]:
    """Three figures: LDC per tooth (constant vs designed, both sides), pitch corrections
    per tooth (um), off-design LDC curves. Returns the file names written; the SVG texts go
    into ``svgs`` (name -> text) when given."""
    files = []
    n = len(const["ldc_nut_roller"])
    teeth = np.arange(1, n + 1)

    def ldc(ax, key):
        ax.plot(teeth, const[key], "o-", label="constant pitch")
        ax.plot(teeth, designed[key], "s-", label=designed_label)

    fig = _per_side(ldc, " contacts", "load-distribution coefficient f_j / (F0 / n z)",
                    f"{name}: load distribution at the design load")
    files += save_figure(fig, out, "loads_ldc", svgs)

    fig, ax = _figure(figsize=(7, 4))
    j = np.arange(1, len(roller_corr_um) + 1)
    ax.plot(j, roller_corr_um, "o-", label="roller p_r,j - p")
    ax.plot(j, nut_corr_um, "s-", label="nut p_n,j - p")
    ax.set_xlabel("pitch index j (between teeth j and j+1)")
    ax.set_ylabel("pitch correction (um)")
    ax.set_title(f"{name}: pitch corrections ({designed_label})")
    ax.grid(alpha=0.3)
    ax.legend()
    files += save_figure(fig, out, "pitch_corrections", svgs)

    def off_curves(ax, key):
        for row in off:
            ax.plot(teeth, row[key], "-", label=f"{row['load_fraction'] * 100:.0f} % ({row['load_N']:.0f} N)")

    fig = _per_side(off_curves, ", design pitches", "load-distribution coefficient",
                    f"{name}: off-design load distribution")
    files += save_figure(fig, out, "off_design", svgs)
    return files


def plot_model_risk(out: Path, name: str, risk: "ModelRisk", svgs: dict[str, str] | None = None) -> list[str]:
    """Two figures of the model-risk study (:class:`~prs_geom.analysis.loads.ModelRisk`):
    ``model_risk_ldc``, the coefficients per tooth of every set of pitch lists under every
    analytic and the FE model at the design load (colour: the lists; line: the model), and
    ``model_risk_loads``, the worst coefficient per side over the load fractions under every
    model and alternative (one column per set of lists)."""
    files = []
    groups: list[tuple[str, str | None]] = []
    for c in risk.cases:
        if (c.pitch_lists, c.designed_with) not in groups:
            groups.append((c.pitch_lists, c.designed_with))
    line_styles = ("--", "-", ":", "-.", (0, (5, 1)), (0, (3, 1, 1, 1, 1, 1)), (0, (1, 3)))
    marker_styles = ("o", "s", "^", "v", "D", "x", "+")
    styles = {m: line_styles[i % len(line_styles)] for i, m in enumerate(risk.models)}
    markers = {m: marker_styles[i % len(marker_styles)] for i, m in enumerate(risk.models)}
    # per tooth: the analytic and the FE model (the alternatives' worst values are in the
    # second figure and the tables)
    per_tooth_models = [m for m in risk.models if m in ("analytic", "fe")] or list(risk.models[:2])

    def label(lists: str, made: str | None, model: str) -> str:
        return f"{lists}{f' ({made})' if made else ''} under {model}"

    def per_tooth(ax, key):
        for gi, (lists, made) in enumerate(groups):
            for model in per_tooth_models:
                c = risk.case(lists, made, model, 1.0)
                v = getattr(c, key)
                ax.plot(np.arange(1, v.size + 1), v, linestyle=styles[model], marker=markers[model], ms=3,
                        color=f"C{gi}", label=label(lists, made, model))

    fig = _per_side(per_tooth, "", "load-distribution coefficient f_j / (F0 / n z)",
                    f"{name}: model risk at the design load ({risk.design_load_n:g} N)")
    fig.axes[0].legend(fontsize=7)
    files += save_figure(fig, out, "model_risk_ldc", svgs)

    fr = np.array(risk.load_fractions) * 100.0
    fig, axes = _figure(2, len(groups), figsize=(4.2 * len(groups), 7), sharey="row", squeeze=False)
    for gi, (lists, made) in enumerate(groups):
        for row, (key, side) in enumerate((("ldc_nut_roller", "nut-roller"), ("ldc_roller_screw", "roller-screw"))):
            ax = axes[row][gi]
            for mi, model in enumerate(risk.models):
                worst = [float(getattr(risk.case(lists, made, model, f), key).max()) for f in risk.load_fractions]
                ax.plot(fr, worst, linestyle=styles[model], marker=markers[model], color=f"C{mi}", label=model)
            ax.axhline(1.0, color="0.6", lw=0.8)
            ax.set_title(f"{lists}{f' ({made})' if made else ''}: {side}", fontsize=9)
            ax.grid(alpha=0.3)
            if row == 1:
                ax.set_xlabel("load (% of the design load)")
        axes[0][0].set_ylabel("worst coefficient, nut-roller")
        axes[1][0].set_ylabel("worst coefficient, roller-screw")
    # the bottom right panel's upper right corner is free: the coefficients there fall toward
    # the design load and rise less above it
    axes[1][-1].legend(fontsize=7, loc="upper right")
    fig.suptitle(f"{name}: model risk over the load (each model and alternative)")
    files += save_figure(fig, out, "model_risk_loads", svgs)
    return files


def plot_tolerance(out: Path, name: str, worst: np.ndarray, per_case: list[tuple[str, np.ndarray]],
                   deterministic: float, svgs: dict[str, str] | None = None) -> list[str]:
    """Histogram and empirical CDF of the worst load-distribution coefficient of a tolerance
    study (``worst``: each sample's worst over both sides and all loads; ``per_case``:
    (label, values) per load); the no-error value as a vertical line."""
    fig, (ax1, ax2) = _figure(1, 2, figsize=(10, 4))
    bins = max(10, min(60, int(np.sqrt(worst.size))))
    ax1.hist(worst, bins=bins, color="C0", alpha=0.8)
    ax1.axvline(deterministic, color="C3", lw=1.2, label=f"no error {deterministic:.3f}")
    ax1.set_xlabel("worst load-distribution coefficient")
    ax1.set_ylabel("samples")
    ax1.set_title("histogram (all loads)")
    ax1.legend()
    for label, v in [("all loads", worst)] + list(per_case):
        s = np.sort(v)
        ax2.step(s, np.arange(1, s.size + 1) / s.size, where="post", label=label)
    ax2.axhline(0.95, color="0.6", lw=0.8, ls="--")
    ax2.set_xlabel("worst load-distribution coefficient")
    ax2.set_ylabel("fraction of samples <= value")
    ax2.set_title("cumulative distribution")
    ax2.grid(alpha=0.3)
    ax2.legend()
    fig.suptitle(f"{name}: worst LDC under the tolerances ({worst.size} samples)")
    return save_figure(fig, out, "tolerance_ldc", svgs)


#: Labels of the pitch variants the rating plots compare.
RATING_LABELS = {"constant_pitch": "constant pitch", "equal_load": "equal-load pitch", "design": "design pitch lists",
                 "robust": "robust pitch"}
#: matplotlib's default colour cycle (tab10), so that the rating figure matches the others.
_COLOURS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b")


# --------------------------------------------------------------------------- light figures
# The rating figure is drawn in every build, and a three-panel matplotlib figure costs about
# 0.4 s (text layout, twice: PNG and SVG), more than the whole budget of the rating stage
# (docs/theory/ratings.md, "Cost"). Line plots need little: one display list of polylines and
# texts, written as SVG text and drawn with Pillow (matplotlib's own image library) at twice
# the size and reduced, which antialiases the lines. About 30 ms for both files.
@dataclass(frozen=True)
class _Series:
    x: np.ndarray
    y: np.ndarray
    colour: str
    dash: str = ""                 # "", "dash" or "dot"
    label: str | None = None


@dataclass(frozen=True)
class _Panel:
    title: str
    xlabel: str
    ylabel: str
    series: tuple[_Series, ...]
    logy: bool = False
    ymin: float | None = None
    vline: float | None = None     # a dotted vertical marker (data x)
    legend: str = "upper right"    # or "lower right"


_DASH = {"": None, "dash": (6.0, 4.0), "dot": (1.5, 3.0)}


def _tick_text(v: float) -> str:
    """A tick label: plain, or 1e5 style for large and small magnitudes."""
    if v != 0 and not 1e-3 <= abs(v) < 1e5:
        m, e = f"{v:.0e}".split("e")
        return f"{m}e{int(e)}"
    return f"{v:g}"


def _ticks(lo: float, hi: float, log: bool) -> np.ndarray:
    """Tick values inside [lo, hi]: 4-6 round numbers, or the decades (with 2 and 5 when the
    range spans less than two) of a log axis."""
    if log:
        k0, k1 = math.floor(math.log10(lo)), math.ceil(math.log10(hi))
        mult = (1.0,) if k1 - k0 > 2 else (1.0, 2.0, 5.0)
        t = np.array([m * 10.0 ** k for k in range(k0, k1 + 1) for m in mult])
    else:
        from matplotlib.ticker import MaxNLocator

        t = np.asarray(MaxNLocator(5).tick_values(lo, hi))
    return t[(t >= lo - 1e-9 * abs(hi - lo)) & (t <= hi + 1e-9 * abs(hi - lo))]


class _Canvas:
    """A display list in pixels (y down): polylines and texts, then SVG or PNG."""

    def __init__(self, width: int, height: int) -> None:
        self.w, self.h = width, height
        self.items: list[tuple] = []

    def line(self, xy: np.ndarray, colour: str, width: float = 1.0, dash: str = "") -> None:
        self.items.append(("line", np.asarray(xy, dtype=np.float64), colour, width, dash))

    def text(self, x: float, y: float, s: str, size: float = 11.0, anchor: str = "mm", colour: str = "#000000",
             rotate: bool = False) -> None:
        """``anchor``: horizontal l/m/r and vertical t/m/b (Pillow's convention)."""
        self.items.append(("text", x, y, s, size, anchor, colour, rotate))

    # -- SVG
    def svg(self) -> str:
        out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{self.w}" height="{self.h}" '
               f'viewBox="0 0 {self.w} {self.h}" font-family="DejaVu Sans, Arial, sans-serif">',
               f'<rect width="{self.w}" height="{self.h}" fill="#ffffff"/>']
        for it in self.items:
            if it[0] == "line":
                _, xy, colour, width, dash = it
                pts = " ".join(f"{x:.2f},{y:.2f}" for x, y in xy)
                da = _DASH[dash]
                extra = f' stroke-dasharray="{da[0]:g},{da[1]:g}"' if da else ""
                out.append(f'<polyline points="{pts}" fill="none" stroke="{colour}" stroke-width="{width:g}"'
                           f' stroke-linejoin="round"{extra}/>')
            else:
                _, x, y, s, size, anchor, colour, rotate = it
                ta = {"l": "start", "m": "middle", "r": "end"}[anchor[0]]
                bl = {"t": "hanging", "m": "central", "b": "alphabetic"}[anchor[1]]
                rot = f' transform="rotate(-90 {x:.2f} {y:.2f})"' if rotate else ""
                out.append(f'<text x="{x:.2f}" y="{y:.2f}" font-size="{size:g}" fill="{colour}" text-anchor="{ta}" '
                           f'dominant-baseline="{bl}"{rot}>{html.escape(s)}</text>')
        out.append("</svg>")
        return "\n".join(out) + "\n"

    # -- PNG
    def png(self, path: Path, scale: int = 2) -> None:
        from PIL import Image, ImageDraw, ImageFont

        font_file = Path(_matplotlib().get_data_path()) / "fonts" / "ttf" / "DejaVuSans.ttf"
        img = Image.new("RGB", (self.w * scale, self.h * scale), "white")
        draw = ImageDraw.Draw(img)
        fonts: dict[float, Any] = {}
        for it in self.items:
            if it[0] == "line":
                _, xy, colour, width, dash = it
                w = max(1, round(width * scale))
                for seg in _dash_segments(xy * scale, _DASH[dash], scale):
                    draw.line([tuple(p) for p in seg], fill=colour, width=w, joint="curve")
                continue
            _, x, y, s, size, anchor, colour, rotate = it
            font = fonts.setdefault(size, ImageFont.truetype(str(font_file), round(size * scale)))
            pil_anchor = anchor[0] + {"t": "t", "m": "m", "b": "s"}[anchor[1]]
            if not rotate:
                draw.text((x * scale, y * scale), s, fill=colour, font=font, anchor=pil_anchor)
                continue
            l, t, r, b = font.getbbox(s, anchor=pil_anchor)
            tile = Image.new("L", (r - l + 2, b - t + 2), 0)
            ImageDraw.Draw(tile).text((-l + 1, -t + 1), s, fill=255, font=font, anchor=pil_anchor)
            tile = tile.rotate(90, expand=True)
            # the anchor point of the unrotated text sits at (-l, -t) in the tile; rotated by 90 deg
            # counter-clockwise it moves to (-t, width - (-l))
            ox, oy = -t + 1, tile.size[1] - (-l + 1)
            img.paste(Image.new("RGB", tile.size, colour), (round(x * scale - ox), round(y * scale - oy)), tile)
        img.reduce(scale).save(path, optimize=False)


def _dash_segments(xy: np.ndarray, pattern: tuple[float, float] | None, scale: int) -> list[np.ndarray]:
    """The polyline ``xy`` (pixels) as one piece, or cut into dashes of ``pattern`` (on, off)."""
    if pattern is None or len(xy) < 2:
        return [xy]
    on, off = pattern[0] * scale, pattern[1] * scale
    seg = np.diff(xy, axis=0)
    s = np.concatenate([[0.0], np.cumsum(np.hypot(seg[:, 0], seg[:, 1]))])
    starts = np.arange(0.0, s[-1], on + off)
    out = []
    for a in starts:                                   # a few dozen dashes per curve
        b = min(a + on, s[-1])
        inner = s[(s > a) & (s < b)]
        t = np.concatenate([[a], inner, [b]])
        out.append(np.column_stack([np.interp(t, s, xy[:, 0]), np.interp(t, s, xy[:, 1])]))
    return out


def _draw_panel(cv: _Canvas, p: _Panel, x0: float, y0: float, w: float, h: float) -> None:
    """One panel: frame, grid and ticks, curves, labels, title and legend in the box at (x0, y0)."""
    xs = np.concatenate([s.x for s in p.series])
    ys = np.concatenate([s.y for s in p.series])
    xlo, xhi = float(xs.min()), float(xs.max())
    if p.logy:
        ylo, yhi = float(ys.min()) / 1.25, float(ys.max()) * 1.25
    else:
        pad = 0.05 * (float(ys.max()) - float(ys.min()) or 1.0)
        ylo, yhi = float(ys.min()) - pad, float(ys.max()) + pad
        if p.ymin is not None:
            ylo = p.ymin
    fy = (lambda v: np.log10(v)) if p.logy else (lambda v: v)
    Y0, Y1 = fy(ylo), fy(yhi)

    def X(v):
        return x0 + (np.asarray(v) - xlo) / (xhi - xlo) * w

    def Yp(v):
        return y0 + h - (fy(np.asarray(v, dtype=np.float64)) - Y0) / (Y1 - Y0) * h

    for t in _ticks(xlo, xhi, False):
        cv.line(np.array([[X(t), y0], [X(t), y0 + h]]), "#e6e6e6")
        cv.text(float(X(t)), y0 + h + 6, _tick_text(t), 10, "mt")
    for t in _ticks(ylo, yhi, p.logy):
        cv.line(np.array([[x0, Yp(t)], [x0 + w, Yp(t)]]), "#e6e6e6")
        cv.text(x0 - 5, float(Yp(t)), _tick_text(t), 10, "rm")
    if p.vline is not None:
        cv.line(np.array([[X(p.vline), y0], [X(p.vline), y0 + h]]), "#999999", 1.0, "dot")
    for s in p.series:
        cv.line(np.column_stack([X(s.x), Yp(s.y)]), s.colour, 1.6, s.dash)
    cv.line(np.array([[x0, y0], [x0 + w, y0], [x0 + w, y0 + h], [x0, y0 + h], [x0, y0]]), "#000000", 1.0)
    cv.text(x0 + w / 2, y0 - 8, p.title, 11, "mb")
    cv.text(x0 + w / 2, y0 + h + 24, p.xlabel, 11, "mt")
    cv.text(x0 - 52, y0 + h / 2, p.ylabel, 11, "mm", rotate=True)
    labelled = [s for s in p.series if s.label]
    ly = y0 + 12 if p.legend == "upper right" else y0 + h - 12 - 16 * (len(labelled) - 1)
    for i, s in enumerate(labelled):
        yy = ly + 16 * i
        cv.line(np.array([[x0 + w - 200, yy], [x0 + w - 176, yy]]), s.colour, 1.6, s.dash)
        cv.text(x0 + w - 170, yy, s.label, 9.5, "lm")


def plot_rating(out: Path, name: str, rating: "RatingResult", svgs: dict[str, str] | None = None) -> list[str]:
    """``rating.png`` and ``rating.svg``: three panels from ``rating``
    (:class:`prs_geom.analysis.rating.RatingResult`, its curves and stiffness): L10 life (h) against the axial load
    for each pitch variant beside the catalogue life (C_a / F)^3 (log scale); axial stiffness
    of the nut against load, single (secant, tangent) and preloaded double nut (dotted: the
    load at which the preload is lost); maximum Hertz pressure per tooth at the largest duty
    load, constant pitch against the graded variants (screw side solid, nut side dashed).
    Drawn by the light renderer above, not matplotlib (cost)."""
    curves, st = rating.curves, rating.stiffness
    F = np.asarray(curves.curve_loads_n) / 1e3
    life = [_Series(F, np.asarray(curves.catalogue_life_hours), "#000000", "dot", "catalogue (C_a / F)^3")]
    life += [_Series(F, np.asarray(v), _COLOURS[i], "", RATING_LABELS.get(k, k))
             for i, (k, v) in enumerate(curves.life_hours.items())]
    stiff = (_Series(st.load_n / 1e3, st.secant, _COLOURS[0], "", "single nut, secant"),
             _Series(st.load_n / 1e3, st.tangent, _COLOURS[0], "dash", "single nut, tangent"),
             _Series(st.external_n / 1e3, st.double_nut_stiffness, _COLOURS[1], "",
                     f"double nut, preload {st.preload_n / 1e3:.3g} kN"))
    press = []
    for i, (k, (p_rs, p_nr)) in enumerate(curves.pressure.items()):
        teeth = np.arange(1, len(p_rs) + 1, dtype=np.float64)
        press.append(_Series(teeth, np.asarray(p_rs), _COLOURS[i], "", RATING_LABELS.get(k, k)))
        press.append(_Series(teeth, np.asarray(p_nr), _COLOURS[i], "dash"))
    panels = (
        _Panel("life from the tooth loads", "axial load (kN)", "L10 life (h)", tuple(life), logy=True),
        _Panel("axial stiffness (dotted: preload lost)", "axial load (kN)", "stiffness (N/um)", stiff, ymin=0.0,
               vline=float(st.double_nut["lift_off_n"]) / 1e3, legend="lower right"),
        _Panel(f"max Hertz pressure at {curves.pressure_load_n / 1e3:.4g} kN (nut side dashed)",
               "tooth (1 = loaded end)", "pressure (MPa)", tuple(press)))
    cv = _Canvas(1500, 470)
    cv.text(750, 14, f"{name}: ratings", 13, "mt")
    for i, p in enumerate(panels):
        _draw_panel(cv, p, 75 + 500 * i, 62, 400, 330)
    cv.png(out / "rating.png")
    text = cv.svg()
    (out / "rating.svg").write_text(text, encoding="utf-8")
    if svgs is not None:
        svgs["rating"] = text
    return ["rating.png", "rating.svg"]
