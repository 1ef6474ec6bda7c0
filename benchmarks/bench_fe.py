"""Finite-element tooth model timings (prs_geom.analysis.fe, prs_geom.analysis.fe.cache).

Run:  python benchmarks/bench_fe.py [--quick]

For the default design at the converged mesh level (``CONVERGED_LEVEL``) over its engaged
teeth (what ``--compliance fe`` uses):

1. cold: the screw, roller and nut influence matrices computed and stored in an empty
   cache folder (goal: <= 30 s on two cores), with the degrees of freedom per part;
2. warm: the same call reading the cache, in this process (median of 5) and in a fresh
   interpreter (the call alone; goal: <= 0.5 s), with that interpreter's import time;
3. the load analysis: ``analyse_loads`` with the FE model (model risk included) against the
   analytic one, as a ratio measured in the same run;
4. without ``--quick``: the 7-tooth sections of the calibration studies and the convergence
   study over levels 0, 1, 2 with the Richardson estimate (docs/theory/fe.md, Convergence);
5. without ``--quick``: the section ends and the body treatment term by term (docs/theory/fe.md,
   "What moves the answer"): the constant-pitch worst coefficient per side from the sections
   cut at the engaged teeth with the 1D bars to the model, one change at a time; the end
   teeth's tooth part against the interior; the worst coefficient for 2, 4 and 8 unloaded
   periods.

``--quick`` skips (4) and (5). Wall times on this machine are noisy; the ratios in (3) are the
comparable numbers.
"""
from __future__ import annotations

import os
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

from prs_geom.analysis.contact import analyse_contact
import numpy as np

from prs_geom.analysis.fe import CONVERGED_LEVEL, DEFAULT_TEETH, convergence_study, influence_matrices
from prs_geom.analysis.loads import analyse_loads
from prs_geom.analysis.fe.cache import cached_influence
from prs_geom.model.design import default_design

FRESH = """
import time, sys
t0 = time.perf_counter()
from prs_geom.model.design import default_design
from prs_geom.analysis.contact import analyse_contact
from prs_geom.analysis.fe.cache import cached_influence
d = default_design(); c = analyse_contact(d)
t1 = time.perf_counter()
r = cached_influence(d, c, folder=sys.argv[1])
t2 = time.perf_counter()
assert all(r.hits.values())
print(f"{t1 - t0:.3f} {t2 - t1:.3f} {'skfem' in sys.modules}")
"""


def main(quick: bool = False) -> None:
    design = default_design()
    n = design.thread.engaged_teeth
    contact = analyse_contact(design)
    print(f"influence matrices, default design, level {CONVERGED_LEVEL}, {n} teeth, {os.cpu_count()} cores")
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) / "fe"
        t0 = time.perf_counter()
        cold = cached_influence(design, contact, folder=folder)
        t_cold = time.perf_counter() - t0
        for m in cold.influence:
            print(f"  {m.part:>7}: {m.n_dofs:7d} dofs, {m.seconds:6.2f} s")
        print(f"cold (computed and stored): {t_cold:.2f} s for {cold.influence.n_dofs} dofs (goal <= 30 s)")
        warm = []
        for _ in range(5):
            t0 = time.perf_counter()
            r = cached_influence(design, contact, folder=folder)
            warm.append(time.perf_counter() - t0)
            assert all(r.hits.values())
        print(f"warm, this process: median {statistics.median(warm) * 1e3:.1f} ms (goal <= 0.5 s)")
        out = subprocess.run([sys.executable, "-c", FRESH, str(folder)], capture_output=True, text=True, check=True)
        imports, call, skfem = out.stdout.split()
        print(f"warm, fresh interpreter: {float(call) * 1e3:.1f} ms for the call (goal <= 0.5 s) after "
              f"{float(imports):.2f} s of imports and the contact stage; scikit-fem imported: {skfem}")


        t0 = time.perf_counter()
        alt = cached_influence(design, contact, folder=folder, extension=0)
        print(f"the alternative's matrices (sections cut at the engaged teeth), cold: {time.perf_counter() - t0:.2f} s, "
              f"a separate cache entry: {not any(alt.hits.values())}")
        from prs_geom.pipeline import load_models

        os.environ["PRS_GEOM_CACHE"] = tmp
        models = load_models(design.with_changes(loads=replace(design.loads, compliance="fe")), contact)
        analytic, fe = models.compare["analytic"], models.model
        t0 = time.perf_counter()
        analyse_loads(design, contact, model=analytic)
        t_a = time.perf_counter() - t0
        t0 = time.perf_counter()
        analyse_loads(design, contact, model=fe, **models.risk_options)
        t_f = time.perf_counter() - t0
        print(f"analyse_loads: analytic {t_a:.3f} s, FE with model risk {t_f:.3f} s: ratio {t_f / t_a:.2f}")
        print(f"cold matrices / analytic analyse_loads: {t_cold / t_a:.0f}")
    if not quick:
        t0 = time.perf_counter()
        mats = influence_matrices(design, level=CONVERGED_LEVEL, teeth=DEFAULT_TEETH, contact=contact)
        print(f"{DEFAULT_TEETH}-tooth sections (calibration studies): {time.perf_counter() - t0:.2f} s, "
              f"{mats.n_dofs} dofs")
        t0 = time.perf_counter()
        study = convergence_study(design, (0, 1, 2), teeth=DEFAULT_TEETH, contact=contact)
        print(f"convergence, levels 0-1-2 of {DEFAULT_TEETH}-tooth sections ({time.perf_counter() - t0:.1f} s): "
              f"largest change of a diagonal entry from level 1 to 2, observed order, Richardson error of level 2")
        for part in ("screw", "roller", "nut"):
            order = study.order[part]
            print(f"  {part:>7}: {study.finest_change[part] * 100:.3f} % (goal <= 0.5 %), order "
                  f"{np.nanmin(order):.2f}-{np.nanmax(order):.2f}, error <= {study.error_estimate[part].max() * 100:.3f} %")
        decomposition(design, contact)


def _worst(design, model) -> str:
    from prs_geom.analysis.loads import forward

    r = forward(design, model=model)
    return f"{r.ldc_nr.max():.4f} / {r.ldc_rs.max():.4f}"


def decomposition(design, contact, level: int = CONVERGED_LEVEL) -> None:
    """(5): what each modelling choice does to the constant-pitch worst coefficient."""
    from dataclasses import replace

    from prs_geom.analysis.fe import InfluenceMatrices
    from prs_geom.analysis.fe.compliance import ALTERNATIVES, FeVariant, body_scale, fe_load_model, pair_matrix
    from prs_geom.analysis.loads import build_model

    n = design.thread.engaged_teeth
    t0 = time.perf_counter()
    ext = influence_matrices(design, level=level, teeth=n, contact=contact)
    cut = influence_matrices(design, level=level, teeth=n, contact=contact, extension=0)
    print(f"section ends and bodies, level {level} ({time.perf_counter() - t0:.1f} s); constant-pitch worst "
          f"coefficient nut-roller / roller-screw:")
    analytic = build_model(design, contact)
    one_d = FeVariant("1d", bodies="1d")
    print(f"  analytic model                                     {_worst(design, analytic)}")
    steps = [("FE cut at the engaged teeth, 1D bars (earlier model)", cut),
             ("  + screw runs on past the nut", InfluenceMatrices(ext.screw, cut.roller, cut.nut)),
             ("  + roller runs on past the nut", InfluenceMatrices(ext.screw, ext.roller, cut.nut)),
             ("  + nut with its real ends", ext)]
    for label, infl in steps:
        print(f"  {label:<51}{_worst(design, fe_load_model(analytic, infl, one_d))}")
    kappa = replace(analytic, body_screw=analytic.body_screw * body_scale(ext.screw),
                    body_roller=analytic.body_roller * body_scale(ext.roller),
                    body_nut=analytic.body_nut * body_scale(ext.nut),
                    compliance=pair_matrix(ext, lambda pi: pi.tooth_matrix()))
    print(f"  {'  + bars scaled to the FE body slope (kappa)':<51}{_worst(design, kappa)}")
    print(f"  {'  + the rest of the FE bodies = the model':<51}{_worst(design, fe_load_model(analytic, ext))}")
    for v in ALTERNATIVES:
        infl = ext if v.extended else cut
        print(f"  alternative {v.name:<39}{_worst(design, fe_load_model(analytic, infl, v))}")
    print("  end teeth's tooth part T_jj against the interior (teeth 6-15), first / last tooth:")
    for part in ext:
        D = np.diag(part.tooth_matrix())
        for b, flank in enumerate(part.flanks):
            block = D[b * n:(b + 1) * n]
            mid = block[5:15].mean()
            cut_block = np.diag(getattr(cut, part.part).tooth_matrix())[b * n:(b + 1) * n]
            cmid = cut_block[5:15].mean()
            print(f"    {flank:<18} model {block[0] / mid - 1:+.2%} / {block[-1] / mid - 1:+.2%}   cut at the "
                  f"engaged teeth {cut_block[0] / cmid - 1:+.2%} / {cut_block[-1] / cmid - 1:+.2%}")
    print("  unloaded periods of the screw and the roller at each end:")
    for e in (2, 4, 8):
        infl = ext if e == 4 else influence_matrices(design, level=level, teeth=n, contact=contact, extension=e)
        print(f"    {e}: {_worst(design, fe_load_model(analytic, infl))}")


if __name__ == "__main__":
    main(quick="--quick" in sys.argv[1:])
