"""The motor/encoder hardware bridge node and its safety layer."""
from swim_ros.exports import lazy_exports

#: the public names by module, each imported on first use
__all__, __getattr__ = lazy_exports(__name__, {
    "braking": ("joint_dynamics_bounds",),
    "conversions": ("BridgeConfig", "BridgeConfigError", "Conversions", "load_bridge_config"),
    "device": ("CounterSample", "Device", "DeviceError"),
    "io_loop": ("IoLoop", "Snapshot"),
    "safety": ("Command", "FaultCode", "SafetyLayer", "SafetyLimits", "fault_names"),
})
