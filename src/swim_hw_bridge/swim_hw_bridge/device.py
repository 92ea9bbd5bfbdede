"""The device layer: one interface for every way the bridge reaches motors and encoders.

A backend (``mf624``, ``serial``, ``emulated``) moves raw numbers only: encoder counter values as the
hardware holds them (modulo 2**counter_bits, so they wrap) and amplifier current commands in amperes.
Unit conversions, unwrapping, velocity estimation and every safety rule live above this layer, once, so a
backend stays small and each one is tested the same way.

Channels, in this order everywhere: hub (alpha), rail (R), heave motor (phi), pitch motor (theta) for the
encoders; heave, pitch for the motors.
"""
from __future__ import annotations

import abc
import dataclasses

ENCODER_CHANNELS = ("hub", "rail", "heave", "pitch")
MOTOR_CHANNELS = ("heave", "pitch")


class DeviceError(RuntimeError):
    """The device failed or is unreachable: a read or write did not complete. The bridge faults on it."""


@dataclasses.dataclass(frozen=True)
class CounterSample:
    """Raw encoder counters read at one instant.

    counts: one per ENCODER_CHANNELS entry, each in [0, 2**counter_bits).
    monotonic_s: time.monotonic() when the read completed (for the stale-read check and velocities).
    sequence: increments by one per fresh sample from the device; a repeat means the device returned old data.
    """

    counts: tuple[int, int, int, int]
    monotonic_s: float
    sequence: int


class Device(abc.ABC):
    """open -> (enable -> [read_counters, write_currents, toggle_enable]* -> disable)* -> close.

    Implementations must not allocate large objects, log or block longer than their stated timeout in
    read_counters, write_currents and toggle_enable: the I/O loop calls them every period.
    """

    #: bits of the hardware counters (values wrap modulo 2**counter_bits)
    counter_bits: int = 32

    @abc.abstractmethod
    def open(self) -> None:
        """Acquire the hardware; outputs at zero current and amplifiers disabled. Raises DeviceError."""

    @abc.abstractmethod
    def read_counters(self) -> CounterSample:
        """The four encoder counters now. Raises DeviceError on a failed or timed-out read."""

    @abc.abstractmethod
    def write_currents(self, heave_a: float, pitch_a: float) -> None:
        """Command the two current-mode amplifiers, amperes (already saturated by the caller)."""

    @abc.abstractmethod
    def toggle_enable(self) -> None:
        """Flip the amplifier-enable output once.

        The amplifiers' enable input goes through a charge-pump (watchdog) circuit that holds them enabled only
        while this line keeps toggling, so a bridge that hangs or dies disables them even though a DAC keeps its
        last value. Called once per loop period while enabled.
        """

    @abc.abstractmethod
    def enable(self) -> None:
        """Start toggling the enable line (amplifiers on, at the current commanded, normally zero)."""

    @abc.abstractmethod
    def disable(self) -> None:
        """Zero the currents, then stop the enable line (amplifiers off). Safe to call in any state."""

    @abc.abstractmethod
    def close(self) -> None:
        """disable() if needed, then release the hardware. Safe to call twice."""
