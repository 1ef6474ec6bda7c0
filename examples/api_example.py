"""The Python API of prs_geom on the built-in default design (README "Python API").

Run: python examples/api_example.py [OUT_DIR]
Prints the theoretical screw pitch diameter and the worst load-distribution coefficient,
designs equal-load pitch lists, meshes the graded design and, with OUT_DIR, builds every
export into it.
"""
import sys

import prs_geom as pg

design = pg.default_design()
result = pg.analyse(design)
print(f"theoretical screw pitch diameter: {result.contact.theoretical_screw_pitch_diameter_mm:.6f} mm")
print(f"worst load-distribution coefficient (constant pitch): {result.loads.max_ldc:.4f}")

graded = pg.design_pitch(design, target="equal")
check = pg.analyse(graded)
print(f"after equal-load pitch design: worst coefficient {check.loads.max_ldc:.12f}")

meshes = pg.build_meshes(graded, tol=0.05)
print(f"meshes: {', '.join(sorted(meshes)[:4])}, ... ({len(meshes)} in all); "
      f"screw volume {meshes['screw'].volume:.1f} mm3")

if len(sys.argv) > 1:
    report = pg.build(graded, sys.argv[1])
    print(f"wrote {len(report['files'])} files to {sys.argv[1]}")
