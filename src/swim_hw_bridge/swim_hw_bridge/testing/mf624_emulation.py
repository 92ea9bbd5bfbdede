"""EMULATIONS of the MF624's Linux interfaces, for tests and dry runs: no card, no driver, no comedilib.

- ``EmulatedComedi``: a stand-in for comedilib's Python module (``import comedi``) with the calls the mf624
  backend makes, shaped like Comedi's mf6x4 driver (subdevices AI, AO: 8 channels of 14 bits, one range
  -10..10 V; DI; DO: 8 bits). It records every analog and digital write, converts with comedilib's own linear law
  (comedi_from_phys / comedi_to_phys, as in comedilib's range.c), and can be told to fail.
- ``EmulatedCounterRegisters``: a file laid out like the card's counter BAR as uio_mf624 exposes it (a file
  standing in for /dev/uioN, a sysfs tree with the map's size and in-page offset), which the backend mmaps
  exactly as it mmaps /dev/uioN. Tests write counts into the IRC registers and read back IRCCTRL.
"""
from __future__ import annotations

import dataclasses
import errno
import math
import os
import struct
from pathlib import Path

from swim_hw_bridge.backends import mf624_registers as registers


@dataclasses.dataclass
class ComediRange:
    """comedi_range: min and max in physical units, unit code (0 = UNIT_volt)."""

    min: float
    max: float
    unit: int = 0


@dataclasses.dataclass
class _Subdevice:
    type: int
    n_chan: int
    maxdata: int
    ranges: tuple[ComediRange, ...]


class EmulatedComedi:
    """Emulation of the comedilib module (SWIG binding names), one emulated MF624 at ``device_path``.

    Records: ``events`` (every write in order: ("ao", channel, raw), ("do", channel, bit)), ``analog_writes``
    (list of (subdevice, channel, range, aref, raw)), ``ao_raw`` (channel -> raw),
    ``digital_writes`` (list of (subdevice, channel, bit)), ``do_bits`` (channel -> bit), ``open_handles``.
    ``ao_volts(channel)`` converts a channel's last raw value back to volts (comedi_to_phys).
    Failure injection: ``fail_open`` (comedi_open returns None, errno ENODEV), ``fail_writes`` (data and dio
    writes return -1, errno EIO).
    """

    COMEDI_SUBD_UNUSED, COMEDI_SUBD_AI, COMEDI_SUBD_AO, COMEDI_SUBD_DI, COMEDI_SUBD_DO, COMEDI_SUBD_DIO = range(6)
    COMEDI_INPUT, COMEDI_OUTPUT = 0, 1
    AREF_GROUND, AREF_COMMON, AREF_DIFF, AREF_OTHER = range(4)
    UNIT_volt, UNIT_mA, UNIT_none = range(3)

    def __init__(self, device_path: str = "/dev/comedi0") -> None:
        self.device_path = device_path
        bipolar10 = (ComediRange(*registers.AO_RANGE_V),)
        self.subdevices = [  # as mf6x4.c sets up the MF624
            _Subdevice(self.COMEDI_SUBD_AI, 8, registers.AO_MAXDATA, bipolar10),
            _Subdevice(self.COMEDI_SUBD_AO, 8, registers.AO_MAXDATA, bipolar10),
            _Subdevice(self.COMEDI_SUBD_DI, 8, 1, (ComediRange(0.0, 1.0, self.UNIT_none),)),
            _Subdevice(self.COMEDI_SUBD_DO, 8, 1, (ComediRange(0.0, 1.0, self.UNIT_none),)),
        ]
        self.analog_writes: list[tuple[int, int, int, int, int]] = []
        self.ao_raw: dict[int, int] = {}
        self.digital_writes: list[tuple[int, int, int]] = []
        self.do_bits: dict[int, int] = {}
        self.dio_directions: dict[tuple[int, int], int] = {}
        self.events: list[tuple[str, int, int]] = []  # ("ao", channel, raw) and ("do", channel, bit), in order
        self.open_handles: set[int] = set()
        self.fail_open = False
        self.fail_writes = False
        self._errno = 0
        self._next_handle = 1

    # --- device -------------------------------------------------------------------------------------------------

    def comedi_open(self, path: str) -> int | None:
        """A handle to the emulated card, or None (errno set) for another path or fail_open."""
        if self.fail_open or path != self.device_path:
            self._errno = errno.ENODEV if self.fail_open else errno.ENOENT
            return None
        handle = self._next_handle
        self._next_handle += 1
        self.open_handles.add(handle)
        return handle

    def comedi_close(self, handle: int) -> int:
        """Close a handle: 0, or -1 with errno EBADF for one not open."""
        if handle not in self.open_handles:
            self._errno = errno.EBADF
            return -1
        self.open_handles.remove(handle)
        return 0

    def comedi_errno(self) -> int:
        """The errno of the last failed call."""
        return self._errno

    def comedi_strerror(self, number: int) -> str:
        """The message of an errno number."""
        return os.strerror(number) if number else "no error"

    # --- queries ------------------------------------------------------------------------------------------------

    def comedi_find_subdevice_by_type(self, handle: int, kind: int, start: int) -> int:
        """The first subdevice of a kind from start on, or -1 (errno ENODEV)."""
        for index in range(start, len(self.subdevices)):
            if self.subdevices[index].type == kind:
                return index
        self._errno = errno.ENODEV
        return -1

    def comedi_get_subdevice_type(self, handle: int, subdevice: int) -> int:
        """A subdevice's kind."""
        return self.subdevices[subdevice].type

    def comedi_get_n_channels(self, handle: int, subdevice: int) -> int:
        """A subdevice's channel count."""
        return self.subdevices[subdevice].n_chan

    def comedi_get_maxdata(self, handle: int, subdevice: int, channel: int) -> int:
        """A subdevice's largest raw value."""
        return self.subdevices[subdevice].maxdata

    def comedi_get_range(self, handle: int, subdevice: int, channel: int, range_index: int) -> ComediRange | None:
        """A subdevice's range by index, or None (errno EINVAL)."""
        ranges = self.subdevices[subdevice].ranges
        if not 0 <= range_index < len(ranges):
            self._errno = errno.EINVAL
            return None
        return ranges[range_index]

    # --- conversions: comedilib's linear law (range.c) ----------------------------------------------------------

    @staticmethod
    def comedi_from_phys(data: float, value_range: ComediRange, maxdata: int) -> int:
        """A physical value as the raw value, rounded and clamped to [0, maxdata]."""
        if value_range is None or not maxdata:
            return 0
        scaled = (data - value_range.min) / (value_range.max - value_range.min) * maxdata
        if scaled < 0:
            return 0
        if scaled > maxdata:
            return maxdata
        return int(math.floor(scaled + 0.5))

    @staticmethod
    def comedi_to_phys(data: int, value_range: ComediRange, maxdata: int) -> float:
        """A raw value as the physical value of its range."""
        return data / maxdata * (value_range.max - value_range.min) + value_range.min

    # --- writes -------------------------------------------------------------------------------------------------

    def comedi_data_write(self, handle: int, subdevice: int, channel: int, range_index: int, aref: int,
                          data: int) -> int:
        """Write a raw value to an analog output: 1, or -1 with errno set."""
        if not self._writable(handle, subdevice, channel, (self.COMEDI_SUBD_AO,)):
            return -1
        if not 0 <= data <= self.subdevices[subdevice].maxdata:
            self._errno = errno.EINVAL
            return -1
        self.analog_writes.append((subdevice, channel, range_index, aref, data))
        self.events.append(("ao", channel, data))
        self.ao_raw[channel] = data
        return 1

    def comedi_dio_config(self, handle: int, subdevice: int, channel: int, direction: int) -> int:
        """Set a DIO channel's direction: 1, or -1 (errno EINVAL) for a subdevice not DIO."""
        if self.subdevices[subdevice].type != self.COMEDI_SUBD_DIO:
            self._errno = errno.EINVAL
            return -1
        self.dio_directions[(subdevice, channel)] = direction
        return 1

    def comedi_dio_write(self, handle: int, subdevice: int, channel: int, bit: int) -> int:
        """Write a bit to a digital output: 1, or -1 with errno set."""
        if not self._writable(handle, subdevice, channel, (self.COMEDI_SUBD_DO, self.COMEDI_SUBD_DIO)):
            return -1
        self.digital_writes.append((subdevice, channel, int(bool(bit))))
        self.events.append(("do", channel, int(bool(bit))))
        self.do_bits[channel] = int(bool(bit))
        return 1

    def _writable(self, handle: int, subdevice: int, channel: int, kinds: tuple[int, ...]) -> bool:
        if handle not in self.open_handles:
            self._errno = errno.EBADF
            return False
        if self.fail_writes:
            self._errno = errno.EIO
            return False
        if self.subdevices[subdevice].type not in kinds or not 0 <= channel < self.subdevices[subdevice].n_chan:
            self._errno = errno.EINVAL
            return False
        return True

    # --- helpers for tests --------------------------------------------------------------------------------------

    def ao_volts(self, channel: int) -> float:
        """An analog output channel's last raw value in volts."""
        subdevice = self.subdevices[1]
        return self.comedi_to_phys(self.ao_raw[channel], subdevice.ranges[0], subdevice.maxdata)


class EmulatedCounterRegisters:
    """A file standing in for /dev/uioN of uio_mf624, with the counter BAR (BADR2) as UIO map ``map_index``.

    Layout: the file holds ``map_index + 1`` pages; map ``map_index`` is mmap'd at offset ``map_index`` pages,
    and BADR2 begins ``in_page_offset`` bytes into it (as uio_mf624 publishes a BAR that is not page aligned).
    A sysfs tree under ``sysfs_root`` gives .../uioN/maps/mapM/size and offset. ``config`` is the backend
    config that points at all of it.
    """

    def __init__(self, directory: Path, name: str = "uio7", map_index: int = registers.UIO_COUNTER_MAP_INDEX,
                 in_page_offset: int = 0x80) -> None:
        import mmap
        self.page_bytes = mmap.PAGESIZE
        self.path = Path(directory) / name
        self.sysfs_root = Path(directory) / "sys" / "class" / "uio"
        self.map_index = map_index
        self.base = map_index * self.page_bytes + in_page_offset  # file offset of BADR2's first register
        self.path.write_bytes(bytes((map_index + 1) * self.page_bytes))
        map_dir = self.sysfs_root / name / "maps" / f"map{map_index}"
        map_dir.mkdir(parents=True)
        (map_dir / "size").write_text(f"0x{self.page_bytes:x}\n")
        (map_dir / "offset").write_text(f"0x{in_page_offset:x}\n")
        (map_dir / "name").write_text("Counter/timer chip\n")

    @property
    def config(self) -> dict[str, object]:
        """The mf624 backend's options that point it at these registers."""
        return {"irc_device_path": str(self.path), "uio_sysfs_root": str(self.sysfs_root),
                "irc_uio_map_index": self.map_index}

    def write_register(self, offset: int, value: int) -> None:
        """Write a 32-bit register at offset (bytes) from the counter BAR."""
        with open(self.path, "r+b") as file:
            file.seek(self.base + offset)
            file.write(struct.pack("<I", value & 0xFFFFFFFF))

    def read_register(self, offset: int) -> int:
        """A 32-bit register at offset (bytes) from the counter BAR."""
        with open(self.path, "rb") as file:
            file.seek(self.base + offset)
            return struct.unpack("<I", file.read(4))[0]

    def set_irc(self, irc_input: int, count: int) -> None:
        """The hardware's count on IRC input 0..3 (any int; stored modulo 2**32 as the 32-bit register)."""
        self.write_register(registers.IRC_REGISTER_OFFSETS[irc_input], count)
