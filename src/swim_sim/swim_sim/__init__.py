"""The dynamics simulator node with disturbances."""
from swim_ros.exports import lazy_exports

#: the public names by module, each imported on first use
__all__, __getattr__ = lazy_exports(__name__, {
    "sensors": ("SensorNoise", "Sensors"),
    "wake_coupling": ("parameter_defaults", "parameters_from_values"),
})
