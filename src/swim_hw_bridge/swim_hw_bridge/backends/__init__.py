"""Backends of the device layer, by name: ``make_device(name, config)``.

``emulated`` (in-process rig, always available), ``serial`` (microcontroller over USB serial, needs pyserial)
and ``mf624`` (Humusoft MF624 through Comedi and uio_mf624). The last two are imported only when asked for,
so a machine without pyserial or comedilib still runs the emulated bridge.
"""
from __future__ import annotations

import importlib
from typing import Any

from swim_hw_bridge.device import Device

#: backend name -> (module, class); every class is constructed as Cls(config: dict)
BACKENDS: dict[str, tuple[str, str]] = {
    "emulated": ("swim_hw_bridge.backends.emulated", "EmulatedDevice"),
    "serial": ("swim_hw_bridge.backends.serial_backend", "SerialDevice"),
    "mf624": ("swim_hw_bridge.backends.mf624", "Mf624Device"),
}


class UnknownBackend(ValueError):
    """A backend name that is not one of BACKENDS, or whose module cannot be imported here."""


def make_device(name: str, config: dict[str, Any]) -> Device:
    """A new, not yet opened device of backend ``name``. Raises UnknownBackend."""
    if name not in BACKENDS:
        raise UnknownBackend(f"unknown backend '{name}'; choose one of {', '.join(BACKENDS)}")
    module_name, class_name = BACKENDS[name]
    try:
        module = importlib.import_module(module_name)
    except ImportError as err:
        raise UnknownBackend(f"backend '{name}' is not available here: {err}") from err
    return getattr(module, class_name)(config)
