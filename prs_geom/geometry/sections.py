"""Axial and normal sections of the thread profiles as exact primitives (no I/O).

Primitives are straight segments and arcs; the DXF exporter writes them as LINE, ARC and
ELLIPSE entities. Coordinates: X along the part axis (mm, part frame z), Y the radius (mm).

* Axial section at the reference angle theta = 0 of the part frame, over [z_lo, z_hi],
  with the graded-pitch warp: every tooth sits at its warped mid-plane W(m_k). Straight
  flanks are segments. The roller's flank is, in the normal section, an arc of radius r_T
  centred on the roller axis; in the axial section (normal-section convention: axial widths
  divided by cos(lambda)) it is an elliptical arc with semi-axes r_T / cos(lambda) along the
  axis and r_T radially, centred on the axis: written as a true ELLIPSE.
* Normal section of one tooth at the pitch radius (docs/theory/geometry.md formulas, no
  cos(lambda) scaling): straight flanks and the roller's true circular ARC.
"""
from __future__ import annotations

import math

import numpy as np

from prs_geom.geometry.helix import PitchWarp
from prs_geom.geometry.primitives import EllipseArc, Segment
from prs_geom.geometry.profiles import ThreadProfile

__all__ = ["axial_section", "normal_section"]


def _clip_segment(p0, p1, lo, hi, kind):
    (x0, y0), (x1, y1) = p0, p1
    if max(x0, x1) <= lo or min(x0, x1) >= hi:
        return None
    def at(x):
        return y0 + (y1 - y0) * (x - x0) / (x1 - x0) if x1 != x0 else y0
    if x0 < lo:
        x0, y0 = lo, at(lo)
    if x1 > hi:
        x1, y1 = hi, at(hi)
    if x1 - x0 <= 1e-12:
        return None
    return Segment((x0, y0), (x1, y1), kind)


def _clip_ellipse(e: EllipseArc, lo: float, hi: float) -> EllipseArc | None:
    """Restrict an arc lying in 0 <= t <= pi (X = cx + a cos t decreasing in t) to lo <= X <= hi."""
    t_from = max(e.start, math.acos(min(1.0, max(-1.0, (hi - e.centre[0]) / e.a))))
    t_to = min(e.end, math.acos(min(1.0, max(-1.0, (lo - e.centre[0]) / e.a))))
    if t_to - t_from <= 1e-12:
        return None
    return EllipseArc(e.centre, e.a, e.b, t_from, t_to, e.kind)


def axial_section(profile: ThreadProfile, warp: PitchWarp, first_mid: float, z_lo: float,
                  z_hi: float, body_radius: float | None = None) -> list:
    """Half axial section (Y >= 0) at theta = 0 between the end planes, closed by the end
    lines (to the axis for external threads, to the body radius for the nut)."""
    p = profile.pitch
    tr = float(profile.tooth_half_width(profile.root_radius))
    tc = profile.tooth_half_width_at_crest()
    rr, rc = profile.root_radius, profile.crest_radius
    k0 = math.floor((z_lo - first_mid) / p) - 2
    k1 = math.ceil((z_hi - first_mid) / p) + 2
    mids = warp(first_mid + p * np.arange(k0, k1 + 1))
    prims = []
    for i, M in enumerate(mids):
        M = float(M)
        for f in profile.flank.axial_outline(M, 0.25 * profile.pitch * profile.cos_lead, profile.cos_lead, rr, rc):
            c = _clip_ellipse(f, z_lo, z_hi) if isinstance(f, EllipseArc) else \
                _clip_segment(f.start, f.end, z_lo, z_hi, f.kind)
            if c is not None:
                prims.append(c)
        c = _clip_segment((M - tc, rc), (M + tc, rc), z_lo, z_hi, "crest")
        if c is not None:
            prims.append(c)
        if i + 1 < len(mids):
            c = _clip_segment((M + tr, rr), (float(mids[i + 1]) - tr, rr), z_lo, z_hi, "root")
            if c is not None:
                prims.append(c)
    # end lines from the profile to the axis (external) or the body (nut)
    for z_e in (z_lo, z_hi):
        k = int(np.argmin(np.abs(mids - z_e)))
        r_e = float(profile.radius_at_offset(z_e - mids[k]))
        far = body_radius if profile.internal else 0.0
        prims.append(Segment((z_e, min(r_e, far)), (z_e, max(r_e, far)), "end"))
    if profile.internal:
        prims.append(Segment((z_lo, body_radius), (z_hi, body_radius), "body"))
    return prims


def normal_section(profile: ThreadProfile) -> list:
    """One tooth in the normal section centred at X = 0, with half roots on both sides."""
    c = profile.cos_lead
    rr, rc = profile.root_radius, profile.crest_radius
    pn = profile.pitch * c     # normal pitch
    quarter = 0.25 * pn
    wr = profile.flank.drawing_half_width(rr, quarter)
    wc = profile.flank.drawing_half_width(rc, quarter)
    prims = [Segment((-0.5 * pn, rr), (-wr, rr), "root"),
             Segment((-wc, rc), (wc, rc), "crest"),
             Segment((wr, rr), (0.5 * pn, rr), "root")]
    return prims + profile.flank.normal_outline(quarter, rr, rc)
