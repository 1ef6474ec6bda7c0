"""Draw docs/img/datum_shifts.png: datum A, the base cut and the ground flanks of a graded nut.

Run from the repository root: ``.venv/bin/python docs/img/datum_shifts.py``. The numbers come
from the machining sheet of examples/graded-pitch.toml (first four teeth of the nut at the
pitch diameter, theta = 0); the grinding shifts are drawn 100 times larger so they can be seen.
"""
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from prs_geom.analysis.machining import machining_sheets  # noqa: E402
from prs_geom.model.io import load_design  # noqa: E402

EXAGGERATE = 100.0


def main() -> None:
    root = Path(__file__).resolve().parents[2]
    d = load_design(root / "examples" / "graded-pitch.toml")
    rows = machining_sheets(d)["nut"].rows
    fig, ax = plt.subplots(figsize=(10, 3.6))
    ax.axvline(0.0, color="k", lw=2)
    ax.text(0.05, 1.02, "datum A\n(end face)", va="bottom", fontsize=9)
    for tooth in range(1, 5):
        lo = next(r for r in rows if r["tooth"] == tooth and r["flank"] == "lower")
        up = next(r for r in rows if r["tooth"] == tooth and r["flank"] == "upper")
        # designed tooth at its true positions; the base cut drawn with its stock and the shifts
        # exaggerated (base = designed - EXAGGERATE x shift), arrows from base to designed
        d0, d1 = lo["designed_position_mm"], up["designed_position_mm"]
        b0 = d0 - EXAGGERATE * lo["axial_shift_um"] * 1e-3
        b1 = d1 - EXAGGERATE * up["axial_shift_um"] * 1e-3
        ax.fill_between([max(b0, 0.0), b1], 0.15, 0.85, color="0.85", label="base cut (with stock)" if tooth == 1 else None)
        ax.fill_between([max(d0, 0.0), d1], 0.25, 0.75, color="C0", alpha=0.7,
                        label="designed tooth (after grinding)" if tooth == 1 else None)
        for base, designed, y in ((b0, d0, 0.1), (b1, d1, 0.9)):
            if abs(designed - base) > 1e-9 and min(base, designed) >= 0:
                ax.annotate("", xy=(designed, y), xytext=(base, y),
                            arrowprops={"arrowstyle": "->", "color": "C3"})
        ax.text(0.5 * (max(d0, 0.0) + d1), 0.5, f"tooth {tooth}", ha="center", va="center", fontsize=8)
        if not lo["on_part"]:
            ax.text(-0.95, 0.05, "lower flank of tooth 1:\nnot on the part (on_part = no)", fontsize=7, color="C3")
    ax.set_xlim(-1.0, 7.5)
    ax.set_ylim(0, 1.25)
    ax.set_yticks([])
    ax.set_xlabel("axial position from datum A at the pitch diameter, theta = 0 (mm)")
    ax.set_title(f"nut of '{d.name}': base cut at p_b with stock, flanks ground to the designed positions "
                 f"(red: shift = designed - base; stock and shifts drawn x{EXAGGERATE:g})", fontsize=9)
    ax.legend(loc="upper right", fontsize=8)
    fig.savefig(Path(__file__).with_suffix(".png"), dpi=110, bbox_inches="tight")


if __name__ == "__main__":
    main()
