"""Analytic geometry in pure numpy: the surfaces everything else is checked against.

Owns the part frames and roller phasing (:mod:`~prs_geom.geometry.frames`), the flank
shapes (:mod:`~prs_geom.geometry.flanks`: straight and arc flanks as objects), the thread
profiles of screw, roller and nut (:mod:`~prs_geom.geometry.profiles`), the graded-pitch
warp of the helical surfaces (:mod:`~prs_geom.geometry.helix`) and exact axial and normal
sections as lines and arcs (:mod:`~prs_geom.geometry.sections`), and the sizes, layout,
fits and stack-up of the carriers, journals, retaining rings and nut ends
(:mod:`~prs_geom.geometry.mechanism`), the datum slot (:mod:`~prs_geom.geometry.datum`), the
end gears: one involute gear and its outline (:mod:`~prs_geom.geometry.gears`), the roller/ring
gear pair and its sizing (:mod:`~prs_geom.geometry.gear_pair`), the pair's checks and running
clearance (:mod:`~prs_geom.geometry.gear_checks`) and their phasing
(:mod:`~prs_geom.geometry.gear_phasing`), and the generic 2D polygon toolkit
(:mod:`~prs_geom.geometry.planar`). No I/O, no mesh library.
"""

__all__: list[str] = []
