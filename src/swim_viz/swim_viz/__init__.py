"""The rig in RViz and Foxglove: its URDF, its frames from joint_states, and markers of the paths."""
from swim_ros.exports import lazy_exports

#: the public names by module, each imported on first use
__all__, __getattr__ = lazy_exports(__name__, {
    "frames": ("moving_transforms", "fixed_transforms", "rig_joints"),
    "live": ("RateGate", "parse_maneuver_request", "fault_changes"),
    "markers": ("TravelledPath", "planned_paths"),
    "urdf": ("rig_urdf", "write_foil_mesh"),
})
