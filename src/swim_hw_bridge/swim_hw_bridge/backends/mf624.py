"""The ``mf624`` backend: the original rig's Humusoft MF624 PCI card on Linux.

- Motor currents: two analog outputs drive current-mode amplifiers through Comedi (comedilib's Python binding,
  Debian package python3-comedilib, ``import comedi``; kernel driver mf6x4). The commanded voltage is
  ``V = I / G`` with G the amplifier's transconductance in A/V (``*_amplifier_gain_a_per_v``, assumed values in
  bridge.yaml), clipped to +-``dac_range_v`` (the MF624's +-10 V), then converted by comedilib's linear law
  ``raw = floor((V - min) / (max - min) * maxdata + 0.5)`` (comedi_from_phys) and written with
  comedi_data_write. A negative gain inverts a channel's polarity.
- Encoders: Comedi's mf6x4 driver has no encoder subdevice, so the four IRC (quadrature) counters are read from
  the card's counter BAR, memory-mapped (see mf624_registers for the offsets, their source, and why the mapping
  is /dev/uioN under uio_mf624 or the PCI sysfs file resource4 when mf6x4 owns the card). Each read is one
  32-bit load per counter, passed on raw (modulo 2**32); the four are read back to back, microseconds apart,
  not latched together.
- Amplifier enable: one digital output (``enable_do_channel``) that toggle_enable flips once per period.

Wiring of the enable line (the charge pump): the DO pin drives a retriggerable monostable (e.g. a 74HC123 with
an RC of about 50 ms, 6 periods of 8 ms) or an AC-coupled diode charge pump; its output is the amplifiers'
enable input. Only a line that keeps toggling holds it on, so a bridge that hangs or dies (the DAC keeping its
last voltage, the DO stuck high or low) disables the amplifiers within the hold time.

Errors are DeviceError: comedilib not importable, /dev/comedi0 or the counter mapping not openable, the wrong
card (no AO/DO subdevice, a range not covering +-dac_range_v, registers outside the mapping), and a failed
comedi call. A current that is not finite writes 0 V and raises.
"""
from __future__ import annotations

import math
import mmap
import os
import time
from pathlib import Path
from typing import Any

from ..device import CounterSample, Device, DeviceError
from . import mf624_registers as registers

DEFAULTS: dict[str, Any] = {
    "comedi_device": "/dev/comedi0",
    "ao_subdevice": -1,
    "heave_ao_channel": 0,
    "pitch_ao_channel": 1,
    "ao_range_index": 0,
    "do_subdevice": -1,
    "enable_do_channel": 0,
    "heave_amplifier_gain_a_per_v": 0.2,
    "pitch_amplifier_gain_a_per_v": 0.2,
    "dac_range_v": 10.0,
    "irc_device_path": "/dev/uio0",
    "irc_uio_map_index": registers.UIO_COUNTER_MAP_INDEX,
    "uio_sysfs_root": "/sys/class/uio",
    "irc_register_offsets": registers.IRC_REGISTER_OFFSETS,
    "encoder_irc_inputs": (0, 1, 2, 3),
    "irc_control_offset": registers.IRC_CONTROL_OFFSET,
    "irc_control_value": registers.IRCCTRL_QUADRATURE_COUNTING,
    "write_irc_control_on_open": True,
    "comedi_module": None,
}


class Mf624Device(Device):
    """Motors and encoders through a Humusoft MF624: Comedi for the analog and digital outputs, mmap for the IRCs.

    Config keys (plain dict; every key has a default; other keys are ignored):

    - ``comedi_device`` (str, "/dev/comedi0"): the MF624's Comedi device (driver mf6x4).
    - ``ao_subdevice`` (int, -1): analog output subdevice; -1 finds the first COMEDI_SUBD_AO (mf6x4: 1).
    - ``heave_ao_channel``, ``pitch_ao_channel`` (int, 0 and 1): DA channels wired to the two amplifiers.
    - ``ao_range_index`` (int, 0): Comedi range of those channels (mf6x4 has one: -10..10 V).
    - ``do_subdevice`` (int, -1): digital output subdevice; -1 finds COMEDI_SUBD_DO (mf6x4: 3), else a DIO
      subdevice, whose channel is then configured as an output.
    - ``enable_do_channel`` (int, 0): the DO bit wired to the enable charge pump.
    - ``heave_amplifier_gain_a_per_v``, ``pitch_amplifier_gain_a_per_v`` (float, 0.2): amplifier
      transconductance (assumed; the bridge passes bridge.yaml's values under these names).
    - ``dac_range_v`` (float, 10.0): commands are clipped to +- this (the MF624's +-10 V).
    - ``irc_device_path`` (str, "/dev/uio0"): the counter mapping, a UIO device of uio_mf624 or a PCI sysfs
      ``resource4`` file (see mf624_registers), or any regular file (tests).
    - ``irc_uio_map_index`` (int, 2): UIO map holding BADR2 (used only when the path's name starts with "uio").
    - ``uio_sysfs_root`` (str, "/sys/class/uio"): where the UIO map's size and in-page offset are read.
    - ``irc_register_offsets`` (4 ints, 0x70 0x74 0x78 0x7C): byte offsets of IRC0..IRC3 in BADR2.
    - ``encoder_irc_inputs`` (4 ints, 0 1 2 3): IRC input wired to hub, rail, heave, pitch.
    - ``irc_control_offset`` (int, 0x6C), ``irc_control_value`` (int, 0): IRCCTRL and the value open() writes
      (quadrature counting, no reset, no filter), if ``write_irc_control_on_open`` (bool, True).
    - ``comedi_module`` (object, None): a stand-in for ``import comedi`` (tests pass EmulatedComedi); the
      constructor's ``comedi_module`` argument does the same.

    Diagnostics: ``clipped_writes`` (commands clipped to the DAC range), ``last_volts`` (heave, pitch),
    ``enable_level`` (the DO level now), ``last_error``.
    """

    def __init__(self, config: dict[str, Any] | None = None, comedi_module: Any = None) -> None:
        self.config = {**DEFAULTS, **{key: value for key, value in (config or {}).items() if key in DEFAULTS}}
        self._comedi = comedi_module if comedi_module is not None else self.config["comedi_module"]
        self.dac_range_v = float(self.config["dac_range_v"])
        self.gains_a_per_v = (float(self.config["heave_amplifier_gain_a_per_v"]),
                              float(self.config["pitch_amplifier_gain_a_per_v"]))
        if not all(math.isfinite(gain) and gain != 0.0 for gain in self.gains_a_per_v):
            raise DeviceError(f"mf624 backend: amplifier gains must be finite and non-zero, got {self.gains_a_per_v}")
        self.ao_channels = (int(self.config["heave_ao_channel"]), int(self.config["pitch_ao_channel"]))
        self.enable_do_channel = int(self.config["enable_do_channel"])
        self._handle: Any = None
        self._outputs_ready = False  # comedi open and both outputs found: writes can go out
        self._ao_subdevice = -1
        self._do_subdevice = -1
        self._ao_ranges: list[Any] = []
        self._ao_maxdata: list[int] = []
        self._fd: int | None = None
        self._map: mmap.mmap | None = None
        self._words: memoryview | None = None
        self._counter_word_indices: tuple[int, ...] = ()
        self._sequence = 0
        self._enabled = False
        self.enable_level = False
        self.clipped_writes = 0
        self.last_volts = (0.0, 0.0)
        self.last_error: str | None = None

    # --- Device interface ---------------------------------------------------------------------------------------

    def open(self) -> None:
        """Open Comedi and the counter mapping; both outputs at 0 V, enable line low."""
        self.close()
        try:
            self._open_comedi()
            self._open_counters()
            self._enabled = False
            self._write_volts(0.0, 0.0)
            self._write_enable_level(False)
        except DeviceError:
            self.close()
            raise

    def read_counters(self) -> CounterSample:
        """The four counters read from the mapped counter registers, with a new sequence number."""
        words = self._words
        if words is None:
            raise DeviceError("mf624 backend: counters are not mapped (open() first)")
        hub, rail, heave, pitch = (words[index] for index in self._counter_word_indices)
        self._sequence += 1
        return CounterSample(counts=(hub, rail, heave, pitch), monotonic_s=time.monotonic(), sequence=self._sequence)

    def write_currents(self, heave_a: float, pitch_a: float) -> None:
        """Write v = i / g to the two analog outputs; a non-finite current writes 0 V and raises DeviceError."""
        if not (math.isfinite(heave_a) and math.isfinite(pitch_a)):
            self._write_volts(0.0, 0.0)
            raise DeviceError(f"mf624 backend: non-finite current command ({heave_a}, {pitch_a}) A; wrote 0 V")
        self._write_volts(heave_a / self.gains_a_per_v[0], pitch_a / self.gains_a_per_v[1])

    def toggle_enable(self) -> None:
        """Flip the enable line's digital output, only while enabled."""
        if self._enabled:
            self._write_enable_level(not self.enable_level)

    def enable(self) -> None:
        """Drive the enable line high and start toggling it; raises DeviceError when not open."""
        self._require_open()
        self._enabled = True
        self._write_enable_level(True)

    def disable(self) -> None:
        """0 V on both outputs, then the enable line low and no more toggles. Never raises (see last_error)."""
        self._enabled = False
        if not self._outputs_ready:
            return
        for action in (lambda: self._write_volts(0.0, 0.0), lambda: self._write_enable_level(False)):
            try:
                action()
            except DeviceError as error:
                # keep going: the enable line must still go low if the DAC write failed, and vice versa
                self.last_error = str(error)

    def close(self) -> None:
        """Disable, then close the Comedi device and release the counter registers' mapping."""
        self.disable()
        handle, self._handle = self._handle, None
        self._outputs_ready = False
        if handle is not None:
            self._comedi.comedi_close(handle)
        if self._words is not None:
            self._words.release()
            self._words = None
        if self._map is not None:
            self._map.close()
            self._map = None
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None

    # --- Comedi -------------------------------------------------------------------------------------------------

    def _open_comedi(self) -> None:
        if self._comedi is None:
            try:
                import comedi  # Debian: apt install python3-comedilib
            except ImportError as error:
                raise DeviceError(
                    "mf624 backend: comedilib's Python binding is missing (`import comedi` failed). Install "
                    "python3-comedilib (Debian/Ubuntu) and make it visible to this Python (a venv made with "
                    "--system-site-packages, or PYTHONPATH=/usr/lib/python3/dist-packages).") from error
            self._comedi = comedi
        comedi = self._comedi
        path = str(self.config["comedi_device"])
        handle = comedi.comedi_open(path)
        if not handle:
            raise DeviceError(f"mf624 backend: cannot open {path}: {self._comedi_error()}. Is the mf6x4 driver "
                              "loaded (lsmod | grep mf6x4), does the device exist, may this user open it?")
        self._handle = handle
        self._ao_subdevice = self._subdevice("ao_subdevice", (comedi.COMEDI_SUBD_AO,), "analog output")
        range_index = int(self.config["ao_range_index"])
        self._ao_ranges, self._ao_maxdata = [], []
        for channel in self.ao_channels:
            channel_count = comedi.comedi_get_n_channels(handle, self._ao_subdevice)
            if not 0 <= channel < channel_count:
                raise DeviceError(f"mf624 backend: analog output channel {channel} does not exist "
                                  f"(subdevice {self._ao_subdevice} has {channel_count})")
            value_range = comedi.comedi_get_range(handle, self._ao_subdevice, channel, range_index)
            maxdata = comedi.comedi_get_maxdata(handle, self._ao_subdevice, channel)
            if value_range is None or maxdata <= 0:
                raise DeviceError(f"mf624 backend: no range {range_index} on analog output {channel}: "
                                  f"{self._comedi_error()}")
            if value_range.min > -self.dac_range_v or value_range.max < self.dac_range_v:
                raise DeviceError(f"mf624 backend: analog output {channel} range {range_index} is "
                                  f"[{value_range.min}, {value_range.max}] V, narrower than dac_range_v "
                                  f"+-{self.dac_range_v} V; pick another ao_range_index or lower dac_range_v")
            self._ao_ranges.append(value_range)
            self._ao_maxdata.append(int(maxdata))
        self._do_subdevice = self._subdevice("do_subdevice", (comedi.COMEDI_SUBD_DO, comedi.COMEDI_SUBD_DIO),
                                             "digital output")
        if comedi.comedi_get_subdevice_type(handle, self._do_subdevice) == comedi.COMEDI_SUBD_DIO:
            if comedi.comedi_dio_config(handle, self._do_subdevice, self.enable_do_channel, comedi.COMEDI_OUTPUT) < 0:
                raise DeviceError(f"mf624 backend: cannot make DIO channel {self.enable_do_channel} an output: "
                                  f"{self._comedi_error()}")
        self._outputs_ready = True

    def _subdevice(self, key: str, kinds: tuple[int, ...], what: str) -> int:
        configured = int(self.config[key])
        if configured >= 0:
            return configured
        for kind in kinds:
            index = self._comedi.comedi_find_subdevice_by_type(self._handle, kind, 0)
            if index >= 0:
                return index
        raise DeviceError(f"mf624 backend: {self.config['comedi_device']} has no {what} subdevice; is it an "
                          f"MF624 (mf6x4 driver)? Set {key} to choose one")

    def _comedi_error(self) -> str:
        try:
            return str(self._comedi.comedi_strerror(self._comedi.comedi_errno()))
        except Exception:  # best effort only: the caller raises DeviceError either way
            return "unknown comedi error"

    def _write_volts(self, heave_v: float, pitch_v: float) -> None:
        self._require_open()
        limit = self.dac_range_v
        clipped = (min(max(heave_v, -limit), limit), min(max(pitch_v, -limit), limit))
        if clipped != (heave_v, pitch_v):
            self.clipped_writes += 1
        comedi = self._comedi
        aref = comedi.AREF_GROUND
        range_index = int(self.config["ao_range_index"])
        for index, volts in enumerate(clipped):
            raw = comedi.comedi_from_phys(volts, self._ao_ranges[index], self._ao_maxdata[index])
            if comedi.comedi_data_write(self._handle, self._ao_subdevice, self.ao_channels[index], range_index,
                                        aref, raw) < 0:
                raise DeviceError(f"mf624 backend: comedi_data_write to AO {self.ao_channels[index]} failed: "
                                  f"{self._comedi_error()}")
        self.last_volts = clipped

    def _write_enable_level(self, level: bool) -> None:
        self._require_open()
        if self._comedi.comedi_dio_write(self._handle, self._do_subdevice, self.enable_do_channel, int(level)) < 0:
            raise DeviceError(f"mf624 backend: comedi_dio_write to DO {self.enable_do_channel} failed: "
                              f"{self._comedi_error()}")
        self.enable_level = level

    def _require_open(self) -> None:
        if not self._outputs_ready:
            raise DeviceError("mf624 backend: the card is not open (open() first)")

    # --- counters -----------------------------------------------------------------------------------------------

    def _open_counters(self) -> None:
        path = Path(str(self.config["irc_device_path"]))
        is_uio = path.name.startswith("uio")
        page = mmap.PAGESIZE
        try:
            self._fd = os.open(path, os.O_RDWR | os.O_SYNC)
        except OSError as error:
            hint = ("is uio_mf624 loaded and bound to the card (ls /sys/class/uio/*/name)? With mf6x4 bound "
                    "instead, use the PCI BAR file .../resource4" if is_uio else "is the path right, may this user "
                    "open it (root or a udev rule)?")
            raise DeviceError(f"mf624 backend: cannot open the counter mapping {path}: {error.strerror}; "
                              f"{hint}") from error
        if is_uio:
            map_index = int(self.config["irc_uio_map_index"])
            map_dir = Path(str(self.config["uio_sysfs_root"])) / path.name / "maps" / f"map{map_index}"
            map_size = _read_sysfs_int(map_dir / "size", default=page)
            in_page_offset = _read_sysfs_int(map_dir / "offset", default=0)
            file_offset = map_index * page  # the UIO convention: map N is mmap'd at offset N pages
        else:
            map_size = os.fstat(self._fd).st_size
            in_page_offset = 0
            file_offset = 0
        offsets = [int(offset) for offset in self.config["irc_register_offsets"]]
        control_offset = int(self.config["irc_control_offset"])
        needed = in_page_offset + max(offsets + [control_offset]) + 4
        if map_size < needed:
            raise DeviceError(f"mf624 backend: the counter mapping {path} is {map_size} bytes, the IRC registers "
                              f"need {needed}; is it the MF624's counter BAR (BADR2 = PCI BAR4, UIO map 2)?")
        if any(offset % 4 for offset in offsets + [control_offset, in_page_offset]):
            raise DeviceError("mf624 backend: IRC register offsets must be multiples of 4 (32-bit registers)")
        try:
            self._map = mmap.mmap(self._fd, map_size, mmap.MAP_SHARED, mmap.PROT_READ | mmap.PROT_WRITE,
                                  offset=file_offset)
        except (OSError, ValueError) as error:
            raise DeviceError(f"mf624 backend: cannot mmap {map_size} bytes of {path} at offset {file_offset}: "
                              f"{error}") from error
        # a uint32 view: indexing it is one aligned 32-bit load or store, as a register access must be
        # (native byte order: little-endian like PCI on the x86 and ARM hosts this runs on)
        self._words = memoryview(self._map).cast("I")
        if self._words.itemsize != 4:
            raise DeviceError("mf624 backend: this platform's C unsigned int is not 32 bits")
        inputs = [int(irc) for irc in self.config["encoder_irc_inputs"]]
        if sorted(inputs) != [0, 1, 2, 3]:
            raise DeviceError(f"mf624 backend: encoder_irc_inputs must assign IRC0..IRC3 once each, got {inputs}")
        self._counter_word_indices = tuple((in_page_offset + offsets[irc]) // 4 for irc in inputs)
        if self.config["write_irc_control_on_open"]:
            self._words[(in_page_offset + control_offset) // 4] = int(self.config["irc_control_value"]) & 0xFFFFFFFF


def _read_sysfs_int(path: Path, default: int) -> int:
    """A UIO sysfs attribute ("0x1000" style); the default when the kernel does not publish it."""
    try:
        return int(path.read_text().strip(), 0)
    except (OSError, ValueError):
        return default
