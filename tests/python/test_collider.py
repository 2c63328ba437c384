"""fluiddemo.bake_collider and Collider.query on the repository's models."""
import numpy as np
import pytest

import fluiddemo
from conftest import REPO, run


def test_crate_distances():
    crate = fluiddemo.bake_collider(str(REPO / "content/models/crate.obj"), resolution=64)
    distance, normal, valid = crate.query(np.array([[0, 0, 0], [0, 0.7, 0], [0.3, 0, 0]], dtype=np.float32))
    assert valid.all()
    # The unit crate: centre 0.5 inside, 0.2 above the top face, 0.2 inside the +x face (texel quantisation).
    assert distance == pytest.approx([-0.5, 0.2, -0.2], abs=0.002)
    assert normal[1] == pytest.approx([0, 1, 0], abs=0.01)
    assert crate.depth_maps == 6


def test_bad_obj_raises_the_cli_message(exe, tmp_path):
    bad = tmp_path / "bad.obj"
    bad.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nbogus 1 2 3\nf 1 2 3\n")
    with pytest.raises(ValueError) as raised:
        fluiddemo.bake_collider(str(bad))
    assert str(raised.value).startswith(f"{bad}:4: unknown or unsupported OBJ statement 'bogus'")
    cli = run(exe, "bake-collider", bad, "--out", tmp_path / "never.fldmaps", check=False)
    assert cli.returncode != 0 and str(raised.value) in cli.stderr
    with pytest.raises(ValueError, match="no such file"):
        fluiddemo.bake_collider(str(tmp_path / "missing.obj"))


def test_open_mesh_is_refused(tmp_path):
    one = tmp_path / "one.obj"
    one.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    with pytest.raises(ValueError, match="the mesh is open: 3 boundary edges"):
        fluiddemo.bake_collider(str(one))


def test_query_wants_points():
    crate = fluiddemo.bake_collider(str(REPO / "content/models/crate.obj"), resolution=16)
    with pytest.raises(ValueError, match=r"points: expected shape \(n, 3\)"):
        crate.query(np.zeros((4, 2)))


def test_quads_slashes_and_negative_indices(tmp_path):
    # The unit cube as six quads, written with v/vt/vn refs and indices relative to the end.
    cube = tmp_path / "cube.obj"
    corners = [(x, y, z) for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)]
    faces = [(1, 2, 4, 3), (5, 7, 8, 6), (1, 5, 6, 2), (3, 4, 8, 7), (1, 3, 7, 5), (2, 6, 8, 4)]
    lines = ["o cube", "vt 0 0", "vn 0 0 1"] + [f"v {x} {y} {z}" for x, y, z in corners]
    lines += ["f " + " ".join(f"{i - 9}/1/1" for i in face) for face in faces]
    cube.write_text("\n".join(lines) + "\n")
    collider = fluiddemo.bake_collider(str(cube), resolution=64)
    distance, _, valid = collider.query([[0, 0, 0], [0, 0, 0.8]])
    assert valid.all() and distance == pytest.approx([-0.5, 0.3], abs=0.002)
    bad = tmp_path / "bad_ref.obj"
    bad.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n")
    with pytest.raises(ValueError, match=r"bad_ref.obj:4: f vertex 4 refers to no vertex \(3 defined so far\)"):
        fluiddemo.bake_collider(str(bad))
