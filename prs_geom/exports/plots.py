"""Plots of the load distribution and pitch design (PNG and SVG), matplotlib Agg backend.

Exporter: takes the numbers of the loads stage (:class:`~prs_geom.analysis.loads.LoadsResult`),
writes files and hands the SVG text on (the HTML report shows it inline).
"""
from __future__ import annotations

import io
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
# SVG element ids from a fixed salt: the same figure gives the same file bytes
matplotlib.rcParams["svg.hashsalt"] = "prs-geom"
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def save_figure(fig, out: Path, stem: str, svgs: dict[str, str] | None = None) -> list[str]:
    """Save ``fig`` as ``stem.png`` and ``stem.svg`` (no timestamp in the SVG) and close it;
    the SVG text also goes into ``svgs[stem]`` when a dict is given."""
    fig.savefig(out / f"{stem}.png", dpi=130, bbox_inches="tight")
    buf = io.BytesIO()
    fig.savefig(buf, format="svg", dpi=130, bbox_inches="tight", metadata={"Date": None})
    (out / f"{stem}.svg").write_bytes(buf.getvalue())
    if svgs is not None:
        svgs[stem] = buf.getvalue().decode("utf-8")
    plt.close(fig)
    return [f"{stem}.png", f"{stem}.svg"]


def _per_side(draw, subtitle: str, ylabel: str, title: str):
    """Two panels, nut-roller and roller-screw, sharing the coefficient axis; ``draw(ax, key)``
    plots the curves of one side (key: "ldc_nut_roller" or "ldc_roller_screw")."""
    fig, axes = plt.subplots(1, 2, figsize=(10, 4), sharey=True)
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

    fig, ax = plt.subplots(figsize=(7, 4))
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


def plot_tolerance(out: Path, name: str, worst: np.ndarray, per_case: list[tuple[str, np.ndarray]],
                   deterministic: float, svgs: dict[str, str] | None = None) -> list[str]:
    """Histogram and empirical CDF of the worst load-distribution coefficient of a tolerance
    study (``worst``: each sample's worst over both sides and all loads; ``per_case``:
    (label, values) per load); the no-error value as a vertical line."""
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 4))
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
