"""The URDF names the frames of swim_viz.frames, and the foil's mesh is the rig's Joukowski foil, closed."""
import struct
import xml.etree.ElementTree as ET

import numpy as np

from swim_model import load_rig
from swim_viz.frames import rig_joints
from swim_viz.urdf import extruded_stl, foil_mesh, foil_outline_m, rig_urdf, write_foil_mesh

RIG = load_rig()


def triangles(stl):
    count = struct.unpack_from("<I", stl, 80)[0]
    assert len(stl) == 84 + 50 * count
    return np.array([struct.unpack_from("<12f", stl, 84 + 50 * i) for i in range(count)]).reshape(count, 4, 3)


def test_urdf_links_and_joints_are_the_frames():
    robot = ET.fromstring(rig_urdf(RIG, "file:///foil.stl"))
    joints = {j.get("name"): j for j in robot.findall("joint")}
    assert set(joints) == {j.name for j in rig_joints(RIG)}
    for joint in rig_joints(RIG):
        element = joints[joint.name]
        assert (element.find("parent").get("link"), element.find("child").get("link")) == (joint.parent, joint.child)
        assert element.get("type") == joint.kind
        np.testing.assert_allclose([float(v) for v in element.find("origin").get("xyz").split()], joint.origin_m)
    links = {link.get("name") for link in robot.findall("link")}
    assert links == {j.child for j in rig_joints(RIG)} | {rig_joints(RIG)[0].parent}
    assert robot.find("link[@name='foil']/visual/geometry/mesh").get("filename") == "file:///foil.stl"


def test_foil_outline_has_the_rigs_chord_and_thickness():
    outline = foil_outline_m(RIG, 2000)
    assert abs(np.ptp(outline[:, 0]) - RIG.foil_chord_m) < 1e-6
    assert abs(np.ptp(outline[:, 1]) - RIG.foil_max_thickness_m) < 1e-5


def test_foil_mesh_is_closed_with_outward_normals_and_the_prisms_volume():
    outline = foil_outline_m(RIG)
    mesh = triangles(foil_mesh(RIG))
    normals, vertices = mesh[:, 0], mesh[:, 1:]
    # divergence theorem: the volume of a closed, outward-oriented mesh is sum(v0 . (v1 x v2)) / 6
    volume = np.sum(np.einsum("ij,ij->i", vertices[:, 0], np.cross(vertices[:, 1], vertices[:, 2]))) / 6.0
    x, y = outline[:, 0], outline[:, 1]
    area = 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)   # shoelace
    assert abs(volume - area * RIG.foil_span_m) < 1e-6 * area * RIG.foil_span_m
    # every edge is shared by exactly two triangles, in opposite directions
    edges = {}
    for triangle in np.round(vertices.astype(float), 7):
        for a, b in ((0, 1), (1, 2), (2, 0)):
            edges[(tuple(triangle[a]), tuple(triangle[b]))] = edges.get((tuple(triangle[a]), tuple(triangle[b])), 0) + 1
    assert all(edges.get((b, a)) == 1 and count == 1 for (a, b), count in edges.items())
    centres = vertices.mean(axis=1)
    assert np.all(np.einsum("ij,ij->i", normals[:, :2], centres[:, :2]) >= -1e-9)   # sides and caps face out


def test_extruded_stl_refuses_a_degenerate_outline():
    import pytest
    with pytest.raises(ValueError):
        extruded_stl(np.zeros((2, 2)), 0.0, -1.0)


def test_write_foil_mesh_is_named_for_its_content(tmp_path):
    first = write_foil_mesh(RIG, tmp_path)
    assert first.read_bytes() == foil_mesh(RIG) and write_foil_mesh(RIG, tmp_path) == first
    other = write_foil_mesh(RIG.replace(foil_chord_m=0.08), tmp_path)
    assert other != first and other.is_file()
