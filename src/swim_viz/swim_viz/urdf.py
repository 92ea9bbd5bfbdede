"""The rig as a URDF, from the rig file: tank, hub arm (the rails), platform, heave link, pitch shaft and foil.

The foil's Joukowski outline (swim_model.joukowski, paper eq. 1) is extruded over its span into an STL mesh.

The frames and joints are swim_viz.frames.rig_joints: one link per frame, one joint per frame, so the URDF and the
transforms published on /tf name the same frames. The pitch joint's angle is theta - phi (frames docstring): a
robot_state_publisher fed joint_states' theta would draw the foil wrongly, which is why swim_viz has its own
publisher of the transforms. The moving parts are drawn in the plane of eq. 40 (z = 0, the water surface) and
above it; the heights and cross-sections below only draw the rig (the model has none of them).
"""
from __future__ import annotations

import hashlib
import struct
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import numpy.typing as npt

from swim_model.joukowski import JoukowskiFoil
from swim_model.rig import RigParameters
from swim_viz.frames import FIXED, PRISMATIC, rig_joints

ROBOT_NAME = "swimming_machine"
#: drawing only: the water's depth in the tank (the paper gives the tank's diameter, not its depth)
TANK_WATER_DEPTH_M = 0.5
#: drawing only: the rails' height above the water and their cross-section (width, thickness)
RAIL_HEIGHT_M, RAIL_WIDTH_M, RAIL_THICKNESS_M = 0.12, 0.04, 0.02
#: drawing only: the platform's size along the rails, across them and its thickness (rig.yaml's platform_inertia
#: assumes a body about 0.25 m across)
PLATFORM_SIZE_M = (0.25, 0.15, 0.03)
#: drawing only: the heave link's height above the water, its width and thickness
LINK_HEIGHT_M, LINK_WIDTH_M, LINK_THICKNESS_M = 0.06, 0.02, 0.01
#: drawing only: the radius of the pitch shaft, from the link down to the foil's top at the water surface
SHAFT_RADIUS_M = 0.004
#: points of the foil's outline in the mesh: 200 keep the drawn profile within 0.1 mm of the map's
FOIL_OUTLINE_POINTS = 200
#: a prismatic joint needs limits in URDF: the platform stays on the rails, within the tank's radius
RAIL_EFFORT_LIMIT_N, RAIL_VELOCITY_LIMIT_M_S = 0.0, 1.0

COLOURS = {"water": (0.2, 0.45, 0.8, 0.25), "rail": (0.6, 0.6, 0.6, 1.0), "platform": (0.3, 0.3, 0.35, 1.0),
           "link": (0.85, 0.55, 0.1, 1.0), "foil": (0.9, 0.2, 0.2, 1.0)}


def foil_outline_m(rig: RigParameters, points: int = FOIL_OUTLINE_POINTS) -> npt.NDArray[np.float64]:
    """The foil's section in its frame, (points, 2), m.

    x runs along the chord toward the leading edge, y normal to it; counter-clockwise from the trailing edge (the
    Joukowski map of eq. 1 for the rig's chord and thickness).
    """
    foil = JoukowskiFoil(rig.foil_chord_m, rig.foil_max_thickness_m, rig.foil_span_m)
    profile = foil.profile(points)
    return np.column_stack([profile.real, profile.imag])


def extruded_stl(outline_m: npt.NDArray[np.float64], top_z_m: float, bottom_z_m: float) -> bytes:
    """A binary STL of the closed prism between two heights (m) over a counter-clockwise outline (N, 2).

    The outline is star-shaped about the origin. N side quads as 2 triangles each, and each cap as a fan of N
    triangles about the origin; outward normals.
    """
    outline = np.asarray(outline_m, dtype=float)
    if outline.ndim != 2 or outline.shape[1] != 2 or len(outline) < 3:
        raise ValueError(f"an outline is (N >= 3, 2) points, got shape {outline.shape}")
    triangles: list[tuple[tuple[float, float, float], ...]] = []
    count = len(outline)
    for i in range(count):
        (x0, y0), (x1, y1) = outline[i], outline[(i + 1) % count]
        a, b = (x0, y0, bottom_z_m), (x1, y1, bottom_z_m)
        c, d = (x1, y1, top_z_m), (x0, y0, top_z_m)
        triangles += [(a, b, c), (a, c, d),                                       # side, facing out
                      ((0.0, 0.0, top_z_m), d, c), ((0.0, 0.0, bottom_z_m), b, a)]   # caps: up, then down
    data = bytearray(b"swim_viz foil".ljust(80, b" "))
    data += struct.pack("<I", len(triangles))
    for vertices in triangles:
        p0, p1, p2 = (np.array(v) for v in vertices)
        normal = np.cross(p1 - p0, p2 - p0)
        length = float(np.linalg.norm(normal))
        data += struct.pack("<3f", *(normal / length if length > 0.0 else normal))
        for vertex in vertices:
            data += struct.pack("<3f", *vertex)
        data += struct.pack("<H", 0)
    return bytes(data)


def foil_mesh(rig: RigParameters) -> bytes:
    """The foil as an STL in its frame: the outline from the water surface (z = 0) down over the span."""
    return extruded_stl(foil_outline_m(rig), 0.0, -rig.foil_span_m)


def write_foil_mesh(rig: RigParameters, directory: Path) -> Path:
    """Write foil_mesh to directory (made if missing); its path.

    The file is named for its content so that rigs of other foils never share a file.
    """
    mesh = foil_mesh(rig)
    path = Path(directory) / f"foil_{hashlib.sha256(mesh).hexdigest()[:16]}.stl"
    if not path.is_file() or path.read_bytes() != mesh:
        path.parent.mkdir(parents=True, exist_ok=True)
        temporary = path.with_suffix(".tmp")
        temporary.write_bytes(mesh)
        temporary.replace(path)
    return path


def _number(value: float) -> str:
    return repr(float(value))


def _vector(*values: float) -> str:
    return " ".join(_number(v) for v in values)


def _visual(link: ET.Element, material: str, geometry: str, size: dict[str, str],
            xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> None:
    visual = ET.SubElement(link, "visual")
    ET.SubElement(visual, "origin", xyz=_vector(*xyz), rpy="0 0 0")
    ET.SubElement(ET.SubElement(visual, "geometry"), geometry, size)
    ET.SubElement(visual, "material", name=material)


def rig_urdf(rig: RigParameters, foil_mesh_uri: str) -> str:
    """The URDF of the rig (frames: swim_viz.frames).

    The foil is drawn by the mesh at foil_mesh_uri (write_foil_mesh; a file:// or package:// URI).
    """
    robot = ET.Element("robot", name=ROBOT_NAME)
    for name, rgba in COLOURS.items():
        ET.SubElement(ET.SubElement(robot, "material", name=name), "color", rgba=_vector(*rgba))
    tank_radius_m = 0.5 * rig.tank_diameter_m
    links = {joint.child: ET.Element("link", name=joint.child) for joint in rig_joints(rig)}
    tank = ET.SubElement(robot, "link", name=rig_joints(rig)[0].parent)
    _visual(tank, "water", "cylinder", {"radius": _number(tank_radius_m), "length": _number(TANK_WATER_DEPTH_M)},
            (0.0, 0.0, -0.5 * TANK_WATER_DEPTH_M))
    _visual(links["hub_arm"], "rail", "box",
            {"size": _vector(rig.tank_diameter_m, RAIL_WIDTH_M, RAIL_THICKNESS_M)}, (0.0, 0.0, RAIL_HEIGHT_M))
    _visual(links["platform"], "platform", "box", {"size": _vector(*PLATFORM_SIZE_M)},
            (0.0, 0.0, RAIL_HEIGHT_M - 0.5 * (RAIL_THICKNESS_M + PLATFORM_SIZE_M[2])))
    _visual(links["heave_link"], "link", "box",
            {"size": _vector(LINK_WIDTH_M, rig.heave_link_length_m, LINK_THICKNESS_M)},
            (0.0, 0.5 * rig.heave_link_length_m, LINK_HEIGHT_M))
    _visual(links["pitch_axis"], "link", "cylinder",
            {"radius": _number(SHAFT_RADIUS_M), "length": _number(LINK_HEIGHT_M)}, (0.0, 0.0, 0.5 * LINK_HEIGHT_M))
    _visual(links["foil"], "foil", "mesh", {"filename": foil_mesh_uri})
    for joint in rig_joints(rig):
        robot.append(links[joint.child])
        element = ET.SubElement(robot, "joint", name=joint.name, type=joint.kind)
        ET.SubElement(element, "parent", link=joint.parent)
        ET.SubElement(element, "child", link=joint.child)
        ET.SubElement(element, "origin", xyz=_vector(*joint.origin_m), rpy=_vector(0.0, 0.0, joint.origin_yaw_rad))
        if joint.kind == FIXED:
            continue
        ET.SubElement(element, "axis", xyz="1 0 0" if joint.kind == PRISMATIC else "0 0 1")
        if joint.kind == PRISMATIC:
            ET.SubElement(element, "limit", lower="0", upper=_number(tank_radius_m),
                          effort=_number(RAIL_EFFORT_LIMIT_N), velocity=_number(RAIL_VELOCITY_LIMIT_M_S))
    ET.indent(robot)
    return '<?xml version="1.0"?>\n' + ET.tostring(robot, encoding="unicode") + "\n"

