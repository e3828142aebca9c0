import warnings

import numpy as np
import pytest
import trimesh

from mavac.geometry.mesh import collada_unit, load_mesh, repair_mesh, units_in_range


def _write_box(path, size):
    trimesh.creation.box([size, size / 2, size / 4]).export(path)
    return path


def _load_quietly(path, units="m"):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a clean closed mesh loads without any warning
        return load_mesh(path, units=units)


@pytest.mark.parametrize("units, size_in_file", [("m", 1.2), ("cm", 120.0), ("mm", 1200.0),
                                                 ("in", 1.2 / 0.0254)])
def test_units_are_converted_to_metres(tmp_path, units, size_in_file):
    mesh = _load_quietly(_write_box(tmp_path / "box.stl", size_in_file), units)
    np.testing.assert_allclose(mesh.extents, [1.2, 0.6, 0.3], rtol=1e-6)
    assert mesh.metadata["mavac_units"] == units
    assert mesh.metadata["mavac_repairs"]["watertight"]
    assert mesh.volume > 0


@pytest.mark.parametrize("suffix", [".stl", ".obj", ".ply", ".dae"])
def test_round_trip_through_each_format(tmp_path, suffix):
    original = trimesh.creation.icosphere(subdivisions=2, radius=0.3)
    original.export(tmp_path / f"sphere{suffix}")
    mesh = _load_quietly(tmp_path / f"sphere{suffix}")
    assert len(mesh.faces) == len(original.faces)
    assert mesh.volume == pytest.approx(original.volume, rel=1e-5)


def test_refuses_unknown_units(tmp_path):
    with pytest.raises(ValueError, match="units must be one of"):
        load_mesh(_write_box(tmp_path / "box.stl", 1.0), units="ft")


def test_refuses_missing_file_and_unknown_type(tmp_path):
    with pytest.raises(ValueError, match="path .* does not exist"):
        load_mesh(tmp_path / "missing.stl")
    (tmp_path / "mesh.step").write_text("ISO-10303-21;")
    with pytest.raises(ValueError, match="unsupported file type '.step'"):
        load_mesh(tmp_path / "mesh.step")


def test_refuses_empty_mesh(tmp_path):
    (tmp_path / "empty.obj").write_text("# no geometry\n")
    with pytest.raises(ValueError, match="empty"):
        load_mesh(tmp_path / "empty.obj")


def test_refuses_nan_and_infinite_vertices(tmp_path):
    (tmp_path / "nan.obj").write_text("v 0 0 0\nv 1 0 0\nv nan 1 0\nv 0 inf 1\nf 1 2 3\nf 1 2 4\n")
    with pytest.raises(ValueError, match="2 vertices with NaN or infinite"):
        load_mesh(tmp_path / "nan.obj")


def test_refuses_a_millimetre_file_read_as_metres(tmp_path):
    path = _write_box(tmp_path / "machine.stl", 1500.0)
    with pytest.raises(ValueError, match=r"machine.stl: mesh is 1500 m across after reading it in 'm', but "
                                         r"a machine or a part is expected to be 0.02 m to 5 m across; "
                                         r"if the file is in millimetres, pass units='mm' \(1.5 m\)"):
        load_mesh(path, units="m")


def test_refuses_a_metre_file_read_as_millimetres(tmp_path):
    path = _write_box(tmp_path / "table.stl", 1.2)
    with pytest.raises(ValueError, match=r"1.2 mm|0.0012 m across after reading it in 'mm'.*units='m' \(1.2 m\)"):
        load_mesh(path, units="mm", role="machine")


def test_part_read_in_the_wrong_unit_names_every_unit_that_fits(tmp_path):
    # a 170 mm boat read as metres: 170 m; as a part it fits in cm (1.7 m) and in mm (0.17 m)
    path = _write_box(tmp_path / "boat.stl", 170.0)
    with pytest.raises(ValueError, match=r"a part is expected to be 0.02 m to 2 m across; pass the file's unit: "
                                         r"units='cm' \(1.7 m\) or units='mm' \(0.17 m\)"):
        load_mesh(path, units="m", role="part")
    assert load_mesh(path, units="mm", role="part").extents.max() == pytest.approx(0.17)


def test_role_ranges_refuse_a_part_sized_machine_and_a_machine_sized_part(tmp_path):
    small = _write_box(tmp_path / "small.stl", 0.1)
    with pytest.raises(ValueError, match="a machine is expected to be 0.3 m to 5 m across"):
        load_mesh(small, units="m", role="machine")
    assert load_mesh(small, units="m", role="part").extents.max() == pytest.approx(0.1)
    big = _write_box(tmp_path / "big.stl", 3.0)
    with pytest.raises(ValueError, match="a part is expected to be 0.02 m to 2 m across"):
        load_mesh(big, units="m", role="part")
    with pytest.raises(ValueError, match="role must be"):
        load_mesh(big, units="m", role="robot")


def test_units_in_range():
    assert units_in_range(40.0, "part") == ["cm", "mm", "in"]  # 40 in = 1.02 m
    assert units_in_range(1.2, "machine") == ["m"]
    assert units_in_range(1e9) == []


def test_refuses_a_size_no_unit_can_explain(tmp_path):
    path = _write_box(tmp_path / "planet.stl", 1e9)
    with pytest.raises(ValueError, match="no unit .* brings it into that range"):
        load_mesh(path, units="mm")


def _dae_with_unit(path, size, meter):
    trimesh.creation.box([size, size / 2, size / 4]).export(path)
    text = path.read_text()
    text = text.replace("<asset>", f'<asset><unit meter="{meter}" name="declared"/>', 1)
    path.write_text(text)
    return path


def test_collada_unit_is_read_and_a_disagreement_warns(tmp_path):
    path = _dae_with_unit(tmp_path / "mm.dae", 1500.0, 0.001)
    assert collada_unit(path) == pytest.approx(0.001)
    mesh = _load_quietly(path, units=None)  # the file's own unit
    assert mesh.extents.max() == pytest.approx(1.5)
    assert mesh.metadata["mavac_units"] == "mm"
    _load_quietly(path, units="mm")  # agrees: no warning
    with pytest.warns(UserWarning, match=r'declares <unit meter="0.001"> \(mm\) but units=.m. was passed'):
        with pytest.raises(ValueError, match="units='mm'"):
            load_mesh(path, units="m")


def test_repairs_are_reported_in_warnings_and_metadata(tmp_path):
    # faces: a good triangle, its duplicate, and a zero-area (collinear) one
    (tmp_path / "bad.obj").write_text(
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 3\nf 1 2 4\n")
    with pytest.warns(UserWarning) as record:
        mesh = load_mesh(tmp_path / "bad.obj")
    messages = " | ".join(str(w.message) for w in record)
    assert "1 degenerate faces" in messages and "1 duplicate faces" in messages
    repairs = mesh.metadata["mavac_repairs"]
    assert repairs["degenerate_faces"] == 1 and repairs["duplicate_faces"] == 1
    assert repairs["unreferenced_vertices"] == 1  # the collinear triangle's far corner
    assert len(mesh.faces) == 1 and len(mesh.vertices) == 3


def test_refuses_a_mesh_with_only_degenerate_faces(tmp_path):
    (tmp_path / "flat.obj").write_text("v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n")
    with pytest.raises(ValueError, match="only degenerate faces"):
        load_mesh(tmp_path / "flat.obj")


def test_open_mesh_is_accepted_with_a_warning(tmp_path):
    box = trimesh.creation.box([1.0, 1.0, 1.0])
    open_box = trimesh.Trimesh(box.vertices, box.faces[:-2])  # one side removed
    open_box.export(tmp_path / "open.ply")
    with pytest.warns(UserWarning, match="not watertight"):
        mesh = load_mesh(tmp_path / "open.ply")
    assert not mesh.metadata["mavac_repairs"]["watertight"]
    assert len(mesh.faces) == 10


def test_inside_out_closed_mesh_is_flipped(tmp_path):
    box = trimesh.creation.box([1.0, 1.0, 1.0])
    trimesh.Trimesh(box.vertices, box.faces[:, ::-1]).export(tmp_path / "inverted.stl")
    with pytest.warns(UserWarning, match="inside out"):
        mesh = load_mesh(tmp_path / "inverted.stl")
    assert mesh.volume == pytest.approx(1.0)
    assert mesh.metadata["mavac_repairs"]["inverted"]


def test_stl_triangle_soup_is_merged_without_warning(tmp_path):
    mesh = _load_quietly(_write_box(tmp_path / "soup.stl", 1.0))
    assert mesh.metadata["mavac_repairs"]["merged_vertices"] > 0  # STL stores 3 per face
    assert len(mesh.vertices) == 8


def test_repair_mesh_counts_on_a_clean_mesh_are_zero():
    counts = repair_mesh(trimesh.creation.icosphere())
    assert counts == {"degenerate_faces": 0, "duplicate_faces": 0, "merged_vertices": 0,
                      "unreferenced_vertices": 0, "flipped_faces": 0, "inverted": False,
                      "watertight_as_loaded": True}


def test_inconsistent_winding_is_flipped_and_reported(tmp_path):
    box = trimesh.creation.box([1.0, 1.0, 1.0])
    faces = box.faces.copy()
    faces[-1] = faces[-1, ::-1]  # one face wound against its neighbours
    trimesh.Trimesh(box.vertices, faces, process=False).export(tmp_path / "patchy.obj")
    with pytest.warns(UserWarning, match=r"flipped 1 faces \(turned over, not removed\)"):
        mesh = load_mesh(tmp_path / "patchy.obj")
    assert mesh.is_winding_consistent and mesh.volume == pytest.approx(1.0)
    assert not mesh.metadata["mavac_repairs"]["inverted"]


@pytest.mark.parametrize("name, text", [("broken.ply", "not a ply\n"), ("broken.dae", "<x/>")])
def test_refuses_unreadable_file(tmp_path, name, text):
    (tmp_path / name).write_text(text)
    with pytest.raises(ValueError, match="could not be read as a mesh"):
        load_mesh(tmp_path / name)



def test_open_mesh_keeps_the_majority_orientation_and_warns_about_normals(tmp_path):
    box = trimesh.creation.box([1.0, 1.0, 1.0])
    faces = box.faces[:-2, ::-1].copy()  # open box (top removed), every face turned inward...
    faces[0] = faces[0, ::-1]  # ...but one
    trimesh.Trimesh(box.vertices, faces, process=False).export(tmp_path / "open.obj")
    with pytest.warns(UserWarning, match="flipped 1 faces .*normals-based stain selection"):
        mesh = load_mesh(tmp_path / "open.obj")
    assert mesh.metadata["mavac_repairs"]["flipped_faces"] == 1
    assert mesh.is_winding_consistent
    # the author's (inward) orientation of the other nine faces is kept
    centre = mesh.vertices.mean(axis=0)
    inward = np.einsum("ij,ij->i", mesh.face_normals, mesh.triangles_center - centre) < 0
    assert inward.all()


@pytest.mark.parametrize("meter", ["metre", "0", "-0.001", "nan"])
def test_a_bad_collada_unit_is_refused_not_read_as_metres(tmp_path, meter):
    path = _dae_with_unit(tmp_path / "bad.dae", 1.5, 1.0)
    path.write_text(path.read_text().replace('meter="1"', f'meter="{meter}"').replace('meter="1.0"', f'meter="{meter}"'))
    assert f'meter="{meter}"' in path.read_text()
    with pytest.raises(ValueError, match=r"<unit meter=.*pass units="):
        load_mesh(path)
    assert _load_quietly(path, units="m").extents.max() == pytest.approx(1.5)  # units= overrides it


def test_a_malformed_collada_file_is_not_blamed_on_pycollada(tmp_path):
    path = _dae_with_unit(tmp_path / "cut.dae", 1.5, 1.0)
    path.write_text(path.read_text()[:600])
    with pytest.raises(ValueError, match="could not be read as a mesh") as error:
        load_mesh(path)
    assert "pycollada" not in str(error.value)


def sliver_box(path):
    """A closed 1 m box with a zero-area sliver closing a T-junction (removing the sliver opens
    it), written to ``path``."""
    box = trimesh.creation.box([1.0, 1.0, 1.0])
    v, f = list(map(tuple, box.vertices)), [tuple(t) for t in box.faces]
    (a, b, c), = [t for t in f if t == tuple(box.faces[0])]
    d_face = next(t for t in f if t != (a, b, c) and {a, b} <= set(t))
    m = len(v)
    v.append(tuple((np.array(v[a]) + np.array(v[b])) / 2))
    f.remove((a, b, c))
    f += [(a, m, c), (m, b, c), (a, b, m)] if (a, b) in [(d_face[i], d_face[(i + 1) % 3]) for i in range(3)] \
        else [(a, m, c), (m, b, c), (b, a, m)]
    mesh = trimesh.Trimesh(np.array(v), np.array(f), process=False)
    assert mesh.is_watertight
    mesh.export(path)
    return path


def loading_warnings(path) -> list[str]:
    """The warnings :func:`load_mesh` gives on ``path``."""
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        load_mesh(path)
    return [str(w.message) for w in seen]


def test_no_watertight_warning_when_our_own_repair_opened_the_mesh(tmp_path):
    said = loading_warnings(sliver_box(tmp_path / "sliver.ply"))
    assert any("degenerate" in w for w in said)
    assert not any("not watertight" in w for w in said), said
