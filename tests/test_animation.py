"""The GLB's animation of one screw revolution (issue 19): node hierarchy, keyframes against
the kinematics formulas (float64 keys to 1e-9, the decoded float32 keys to float32
rounding), keys less than 180 degrees apart, and the Khronos validator.

Reference formulas (independent of prs_geom.analysis.kinematics, docs/theory/kinematics.md):
carrier w_c / w_s = r_s / (r_s + r_n) (Willis' formula with the nut held), roller spin
relative to the carrier -w_c r_n / r_r, nut travel -h L_s per screw turn (h = +1 right
hand), roller k's rest pose R_z(psi_k) T_x(a) R_z(-n_s psi_k) in the carrier.
"""
from __future__ import annotations

import json
import math
import struct
from pathlib import Path

import numpy as np
import pytest

from readers import khronos_issues
from prs_geom.exports.scene import ANIMATION_PERIOD_S, assembly_scene, glb_bytes, mechanism_animation
from prs_geom.mesh.assembly import build_assembly
from prs_geom.model.design import Nut, PRSDesign, Roller, Screw, Thread, default_design

DESIGNS = {
    "default": default_design,
    "four-start-seven-rollers-left": lambda: PRSDesign(
        name="s4z7", thread=Thread(hand="left"), screw=Screw(pitch_diameter_mm=16.0, starts=4),
        roller=Roller(pitch_diameter_mm=8.0, count=7), nut=Nut(pitch_diameter_mm=32.0, starts=4, outer_diameter_mm=46.0)),
}


def rz(t: np.ndarray) -> np.ndarray:
    c, s = np.cos(t), np.sin(t)
    R = np.zeros(np.shape(t) + (3, 3))
    R[..., 0, 0], R[..., 0, 1], R[..., 1, 0], R[..., 1, 1], R[..., 2, 2] = c, -s, s, c, 1.0
    return R


def quat_matrix(q: np.ndarray) -> np.ndarray:
    x, y, z, w = np.moveaxis(np.asarray(q, dtype=np.float64), -1, 0)
    return np.stack([np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], -1),
                     np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], -1),
                     np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], -1)], -2)


def expected(d: PRSDesign, theta: np.ndarray) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """(rotation matrices, translations mm) of every animated node at screw angles theta."""
    rs, rr, rn = (0.5 * x.pitch_diameter_mm for x in (d.screw, d.roller, d.nut))
    h = 1.0 if d.thread.hand == "right" else -1.0
    wc = rs / (rs + rn)
    travel = -h * d.screw.starts * d.thread.pitch_mm * theta / (2 * math.pi)
    zero = np.zeros_like(theta)
    axial = np.stack([zero, zero, travel], -1)
    out = {"screw": (rz(theta), np.zeros((len(theta), 3))),
           "nut_assembly": (rz(zero), axial),
           "carrier": (rz(wc * theta), axial)}
    a = 0.5 * (d.screw.pitch_diameter_mm + d.roller.pitch_diameter_mm)
    for k in range(d.roller.count):
        psi = 2 * math.pi * k / d.roller.count
        spin = psi - d.screw.starts * psi - wc * rn / rr * theta
        t = np.tile([a * math.cos(psi), a * math.sin(psi), 0.0], (len(theta), 1))
        out[f"roller_{k}"] = (rz(spin), t)
    return out


@pytest.fixture(scope="module", params=sorted(DESIGNS))
def animated(request):
    d = DESIGNS[request.param]()
    asm = build_assembly(d, tol=0.05)
    return d, asm, assembly_scene(asm, d.name, animate=True)


def test_float64_keys_follow_the_formulas(animated):
    d, asm, scene = animated
    (anim,) = scene.animations
    theta = 2 * math.pi * anim.times_s / ANIMATION_PERIOD_S
    assert theta[0] == 0 and theta[-1] == pytest.approx(2 * math.pi, abs=1e-15)
    ref = expected(d, theta)
    assert set(anim.channels) == set(ref)
    for node, paths in anim.channels.items():
        R, t = ref[node]
        if "rotation" in paths:
            np.testing.assert_allclose(quat_matrix(paths["rotation"]), R, atol=1e-9, rtol=0, err_msg=node)
            # keys less than 180 deg apart: consecutive quaternions on the same side
            q = paths["rotation"]
            assert np.all(np.einsum("ij,ij->i", q[1:], q[:-1]) > 0.0), node
        if "translation" in paths:
            np.testing.assert_allclose(paths["translation"], t, atol=1e-9, rtol=0, err_msg=node)


def test_rest_pose_of_every_part_is_its_placement(animated):
    d, asm, scene = animated
    placed = {name: T for name, _, T in scene.placed()}
    assert set(placed) == set(asm.placed)
    for name, (_, T, _) in asm.placed.items():
        np.testing.assert_allclose(placed[name], T, atol=1e-12, err_msg=name)


def _glb(data: bytes) -> tuple[dict, bytes]:
    magic, version, total = struct.unpack("<4sII", data[:12])
    assert (magic, version, total) == (b"glTF", 2, len(data))
    n = struct.unpack("<I", data[12:16])[0]
    doc = json.loads(data[20:20 + n])
    m = struct.unpack("<I", data[20 + n:24 + n])[0]
    return doc, data[28 + n:28 + n + m]


def _accessor(doc: dict, blob: bytes, i: int) -> np.ndarray:
    acc = doc["accessors"][i]
    view = doc["bufferViews"][acc["bufferView"]]
    width = {"SCALAR": 1, "VEC3": 3, "VEC4": 4}[acc["type"]]
    assert acc["componentType"] == 5126
    a = np.frombuffer(blob, np.float32, acc["count"] * width, view["byteOffset"] + acc.get("byteOffset", 0))
    return a.reshape(acc["count"], width) if width > 1 else a


def test_decoded_glb_keys_agree_to_float32(animated):
    """The GLB read back with a plain JSON + struct reader: each channel's keys are the
    formulas' values rounded to float32 (translations in metres)."""
    d, asm, scene = animated
    doc, blob = _glb(glb_bytes(scene))
    (anim,) = doc["animations"]
    names = [n["name"] for n in doc["nodes"]]
    # rollers are children of the carrier node
    carrier = doc["nodes"][names.index("carrier")]
    assert {names[c] for c in carrier["children"]} >= {f"roller_{k}" for k in range(d.roller.count)}
    times = None
    seen = set()
    for ch in anim["channels"]:
        node, path = names[ch["target"]["node"]], ch["target"]["path"]
        sampler = anim["samplers"][ch["sampler"]]
        assert sampler["interpolation"] == "LINEAR"
        t = _accessor(doc, blob, sampler["input"])
        times = t if times is None else times
        np.testing.assert_array_equal(t, times)
        theta = 2 * math.pi * t.astype(np.float64) / ANIMATION_PERIOD_S
        R, tr = expected(d, 2 * math.pi * np.arange(len(t)) / (len(t) - 1))[node]
        keys = _accessor(doc, blob, sampler["output"]).astype(np.float64)
        if path == "rotation":
            np.testing.assert_allclose(quat_matrix(keys), R, atol=4e-7, err_msg=node)
        else:
            np.testing.assert_allclose(keys, tr * 1e-3, atol=1e-9, rtol=2e-7, err_msg=node)
        assert np.all(np.abs(theta - 2 * math.pi * np.arange(len(t)) / (len(t) - 1)) < 1e-6)
        seen.add((node, path))
    assert ("screw", "rotation") in seen and ("nut_assembly", "translation") in seen
    assert {("carrier", "rotation"), ("carrier", "translation")} <= seen
    assert {(f"roller_{k}", "rotation") for k in range(d.roller.count)} <= seen


def test_animated_glb_passes_the_khronos_validator(animated, tmp_path):
    d, asm, scene = animated
    glb = tmp_path / "a.glb"
    glb.write_bytes(glb_bytes(scene))
    issues = khronos_issues(glb, tmp_path)
    assert issues["numErrors"] == 0, issues["messages"][:10]
    assert issues["numWarnings"] == 0, issues["messages"][:10]


def test_design_outside_the_kinematics_gets_a_still_scene():
    """The kinematics refuses designs off the standard nut sizing; their scene is flat and
    still rather than wrong."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")     # the design model warns about the broken sizing too
        d = PRSDesign(nut=Nut(pitch_diameter_mm=40.4, outer_diameter_mm=56.0))
    asm = build_assembly(d, tol=0.1, gears=False, mechanism=False)
    scene = assembly_scene(asm, animate=True)
    assert scene.animations == ()
    assert [n.name for n in scene.nodes] == list(asm.placed)
    with pytest.raises(ValueError):
        mechanism_animation(d)
