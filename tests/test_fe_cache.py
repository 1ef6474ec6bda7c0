"""The influence-matrix cache (prs_geom.analysis.fe.cache on prs_geom.runtime.cache): keyed by geometry, material and code,
never stale, written atomically into its own folder only, and robust to damaged entries.

A 5-tooth section at mesh level 0 keeps each computation under a second."""
from __future__ import annotations

import os
from dataclasses import replace

import numpy as np
import pytest

from prs_geom.analysis.fe import cache as fe_cache
from prs_geom.analysis.contact import analyse_contact
from prs_geom.analysis.fe import part_sections
from prs_geom.model.design import default_design

LEVEL, TEETH = 0, 5


@pytest.fixture(scope="module")
def design():
    d = default_design()
    return d.with_changes(thread=replace(d.thread, engaged_teeth=TEETH))


def _get(design, folder, **kw):
    return fe_cache.cached_influence(design, level=LEVEL, teeth=TEETH, folder=folder, **kw)


def _files(root):
    return sorted(str(p.relative_to(root)) for p in root.rglob("*") if p.is_file())


def test_second_call_reads_identical_matrices(design, tmp_path):
    folder = tmp_path / "cache"
    ticks = []
    first = _get(design, folder, progress=lambda s, d, t: ticks.append((s, d, t)))
    assert first.hits == {"screw": False, "roller": False, "nut": False} and first.stored
    assert ticks[0] == ("fe matrices", 0, 3) and ticks[-1] == ("fe matrices", 3, 3)
    again = _get(design, folder)
    assert again.hits == {"screw": True, "roller": True, "nut": True}
    for a, b in zip(first.influence, again.influence):
        for name in ("matrix", "axial_position_mm", "axial_sign", "body", "local", "contacts_per_ring",
                     "band_half_width_mm"):
            np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
        assert (a.part, a.flanks, a.level, a.teeth, a.n_dofs, a.support_face) == \
               (b.part, b.flanks, b.level, b.teeth, b.n_dofs, b.support_face)
        assert a.body_per_pitch == b.body_per_pitch and a.pitch_mm == b.pitch_mm
    # only the three entries, in the cache folder, nothing else anywhere under tmp_path
    assert _files(tmp_path) == sorted(f"cache/{p}-{first.keys[p][:32]}.npz" for p in ("nut", "roller", "screw"))


def test_key_follows_material_geometry_and_code(design, tmp_path, monkeypatch):
    """A change of the nut's material is a new nut entry and a new roller entry (the
    roller's nut-side Hertz band depends on the nut's modulus), the screw is read; a change
    of the code (its fingerprint) is a new entry for every part: a stale matrix is never read."""
    folder = tmp_path / "cache"
    base = _get(design, folder)
    mats = design.materials
    softer = design.with_changes(materials=replace(mats, nut=replace(mats.nut, youngs_modulus_mpa=200_000.0)))
    r = _get(softer, folder)
    assert r.hits == {"screw": True, "roller": False, "nut": False}
    assert r.keys["nut"] != base.keys["nut"] and r.keys["screw"] == base.keys["screw"]
    band = r.influence.roller.band_half_width_mm / base.influence.roller.band_half_width_mm
    assert band[0] > 1.0 and band[1] == 1.0          # nut side wider on a softer nut, screw side same
    assert not np.allclose(r.influence.nut.matrix, base.influence.nut.matrix, rtol=1e-3)
    # the installation moves the screw's support only
    cc = design.with_changes(loading=replace(design.loading, installation="compression-compression"))
    r = _get(cc, folder)
    assert r.hits == {"screw": False, "roller": True, "nut": True}
    # the load moves the Hertz band of every part
    heavier = design.with_changes(loading=replace(design.loading, axial_load_n=30_000.0))
    assert not any(_get(heavier, folder).hits.values())
    monkeypatch.setattr(fe_cache, "code_fingerprint", lambda: "another version of the FE code")
    r = _get(design, folder)
    assert not any(r.hits.values()) and r.keys["screw"] != base.keys["screw"]


def test_key_is_the_section_description(design):
    """The key covers every number of the section (profile, flanks, Hertz bands, material,
    support) at full precision: a 1e-12 mm change of a contact radius is a new key."""
    secs = part_sections(design, analyse_contact(design))
    s = secs["nut"]
    fl = s.flanks[0]
    moved = replace(s, flanks=(replace(fl, contact_radius_mm=fl.contact_radius_mm + 1e-12),))
    assert fe_cache.part_key(s, LEVEL, TEETH, "x") != fe_cache.part_key(moved, LEVEL, TEETH, "x")
    assert fe_cache.part_key(s, LEVEL, TEETH, "x") != fe_cache.part_key(s, LEVEL + 1, TEETH, "x")
    assert fe_cache.part_key(s, LEVEL, TEETH, "x") == fe_cache.part_key(replace(s), LEVEL, TEETH, "x")


def test_damaged_or_foreign_entries_are_recomputed(design, tmp_path):
    folder = tmp_path / "cache"
    base = _get(design, folder)
    path = folder / f"screw-{base.keys['screw'][:32]}.npz"
    path.write_bytes(b"not a zip file")
    r = _get(design, folder)
    assert r.hits["screw"] is False and r.hits["nut"] is True
    np.testing.assert_array_equal(r.influence.screw.matrix, base.influence.screw.matrix)
    assert path.read_bytes()[:2] == b"PK"                                     # replaced
    # an entry whose stored description is another section's (a key collision) is not used
    other = folder / f"nut-{base.keys['nut'][:32]}.npz"
    path.write_bytes(other.read_bytes())
    assert _get(design, folder).hits["screw"] is False


def test_a_tampered_matrix_is_detected_and_recomputed(design, tmp_path):
    """An influence matrix multiplied by 1000 in the cache file (its key and
    description left as they were) fails the checksum: recomputed, replaced, warned."""
    folder = tmp_path / "cache"
    base = _get(design, folder)
    path = folder / f"roller-{base.keys['roller'][:32]}.npz"
    with np.load(path, allow_pickle=False) as z:
        stored = {k: np.array(z[k]) for k in z.files}
    stored["matrix"] = stored["matrix"] * 1000.0
    np.savez(path, **stored)
    r = _get(design, folder)
    assert r.hits == {"screw": True, "roller": False, "nut": True}
    assert len(r.warnings) == 1 and "roller influence matrix" in r.warnings[0] and "checksum" in r.warnings[0]
    np.testing.assert_array_equal(r.influence.roller.matrix, base.influence.roller.matrix)
    # the entry was rewritten and reads clean again
    again = _get(design, folder)
    assert again.hits["roller"] is True and again.warnings == ()
    # an entry of the old format (no checksum) is not trusted either
    with np.load(path, allow_pickle=False) as z:
        old = {k: np.array(z[k]) for k in z.files if k not in ("key", "checksum")}
    np.savez(path, **old)
    assert _get(design, folder).hits["roller"] is False


@pytest.mark.skipif(os.name != "posix" or os.geteuid() == 0, reason="needs a read-only folder (not root)")
def test_unwritable_cache_still_gives_the_matrices(design, tmp_path):
    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(0o500)
    try:
        r = _get(design, folder / "fe")
        assert r.stored is False and not any(r.hits.values())
        assert r.influence.screw.matrix.shape == (TEETH, TEETH)
    finally:
        folder.chmod(0o700)


def test_unwritable_cache_path_is_reported(design, tmp_path):
    """A cache 'folder' that is a file cannot be written (also as root): reported, not fatal."""
    blocker = tmp_path / "file"
    blocker.write_text("mine")
    r = _get(design, blocker / "fe")
    assert r.stored is False and r.influence.nut.matrix.shape == (TEETH, TEETH)
    assert blocker.read_text() == "mine"


def test_cache_folder_follows_the_environment(monkeypatch, tmp_path):
    monkeypatch.setenv("PRS_GEOM_CACHE", str(tmp_path / "c"))
    assert fe_cache.cache_dir() == tmp_path / "c" / "fe"
    monkeypatch.delenv("PRS_GEOM_CACHE")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "x"))
    assert fe_cache.cache_dir() == tmp_path / "x" / "prs-geom" / "fe"
