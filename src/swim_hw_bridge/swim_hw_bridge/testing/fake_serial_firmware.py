"""An EMULATION of the rig's microcontroller firmware, for tests and benchmarks: no hardware is involved.

``FakeSerialFirmware`` runs in a thread on one end of a byte stream (the master side of a pseudo-terminal
whose slave side ``SerialDevice`` opens) and behaves as serial_protocol's docstring says the device must:
HELLO -> HELLO_REPLY, STATE_REQUEST -> STATE, COMMAND -> outputs, the command watchdog and the enable charge pump.

It is written from that specification independently of ``serial_protocol`` (its own bitwise CRC, its own COBS,
its own struct layouts; it imports nothing from the host side), so a mistake on either side shows up as a failed
exchange instead of cancelling out. The counters are whatever the test sets; the outputs are only recorded.
Fault injection for tests: replies written in several delayed chunks, garbage or a truncated frame before a
reply, a corrupted CRC, late replies, muteness, a board that stops reading, and disconnect (closing the master end).
``PtyRig`` puts it behind a pseudo-terminal and a stable symlink (as /dev/serial/by-id/... names a board), so a
test can pull the cable and plug a board in again under the same name.
"""
from __future__ import annotations

import collections
import os
import select
import struct
import threading
import time
import tty
from pathlib import Path
from typing import Any, Sequence

_HELLO, _COMMAND, _STATE_REQUEST, _HELLO_REPLY, _STATE = 0x01, 0x02, 0x03, 0x81, 0x83
_ENABLE, _TOGGLE, _CLEAR_WATCHDOG = 0x01, 0x02, 0x04
_OUTPUTS_ENABLED, _WATCHDOG_TRIPPED, _TOGGLE_STALE = 0x0001, 0x0002, 0x0004


def _crc16_bitwise(data: bytes) -> int:
    crc = 0xFFFF
    for byte in data:
        crc ^= byte << 8
        for _ in range(8):
            crc = (crc << 1) ^ 0x1021 if crc & 0x8000 else crc << 1
            crc &= 0xFFFF
    return crc


def _stuff(body: bytes) -> bytes:
    """COBS, written block by block from the specification."""
    out = bytearray()
    block = bytearray()
    ended_on_full_block = False
    for byte in body:
        ended_on_full_block = False
        if byte == 0:
            out += bytes([len(block) + 1]) + block
            block.clear()
        else:
            block.append(byte)
            if len(block) == 254:
                out += b"\xff" + block
                block.clear()
                ended_on_full_block = True
    if not ended_on_full_block:
        out += bytes([len(block) + 1]) + block
    return bytes(out)


def _unstuff(data: bytes) -> bytes | None:
    out = bytearray()
    position = 0
    while position < len(data):
        code = data[position]
        block = data[position + 1:position + code]
        if code == 0 or len(block) != code - 1 or 0 in block:
            return None
        out += block
        position += code
        if code < 255 and position < len(data):
            out += b"\x00"
    return bytes(out)


class FakeSerialFirmware:
    """Emulated firmware on file descriptor ``fd`` (it owns it: disconnect() and stop() close it).

    Observations for tests: ``applied_currents_ua`` (heave, pitch), ``outputs_enabled``, ``watchdog_tripped``,
    ``toggle_stale``, ``rx_error_count``, ``commands`` (recent (sequence, heave_ua, pitch_ua, flags)),
    ``state_requests``. Set ``counts`` (4 ints) at any time.
    """

    def __init__(self, fd: int, counter_bits: int = 32, command_timeout_ms: int = 50, toggle_timeout_ms: int = 50,
                 protocol_version: int = 1) -> None:
        self.fd = fd
        self.counter_bits = counter_bits
        self.command_timeout_ms = command_timeout_ms
        self.toggle_timeout_ms = toggle_timeout_ms
        self.protocol_version = protocol_version
        self.counts = [0, 0, 0, 0]
        # fault injection (tests set these; each *_next_* applies to the next reply only)
        self.reply_chunks = 1
        self.reply_chunk_delay_s = 0.0
        self.garbage_before_next_reply = b""
        self.truncated_frame_before_next_reply = False
        self.corrupt_next_reply_crc = False
        self.delay_next_reply_s = 0.0
        self.muted = False
        self.reading = True  # False: stop reading the port (a hung board), so the host's output buffer fills
        # firmware state
        self.lock = threading.Lock()
        self.sequence = 0
        self.rx_error_count = 0
        self.state_requests = 0
        self.commands: collections.deque[tuple[int, int, int, int]] = collections.deque(maxlen=1000)
        self.enable_requested = False
        self.watchdog_tripped = False
        self.commanded_currents_ua = (0, 0)
        self.last_command_sequence = 0
        self.last_command_time = 0.0
        self.last_toggle_phase: int | None = None
        self.last_toggle_time = 0.0
        self._start_time = time.monotonic()
        self._buffer = bytearray()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="FakeSerialFirmware", daemon=True)

    # --- control ------------------------------------------------------------------------------------------------

    def start(self) -> FakeSerialFirmware:
        """Start the firmware's thread; itself."""
        self._thread.start()
        return self

    def stop(self) -> None:
        """Stop the firmware's thread and close the file descriptor."""
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(timeout=2.0)
        self._close_fd()

    def disconnect(self) -> None:
        """Pull the cable: stop and close the master end, so the host's next read or write fails."""
        self.stop()

    # --- observations -------------------------------------------------------------------------------------------

    @property
    def toggle_stale(self) -> bool:
        """ENABLE is asked for but ENABLE_TOGGLE stopped changing within toggle_timeout_ms."""
        return self.enable_requested and time.monotonic() - self.last_toggle_time > self.toggle_timeout_ms / 1000

    @property
    def outputs_enabled(self) -> bool:
        """Whether the outputs are on: enabled, watchdog not tripped, toggle not stale."""
        return self.enable_requested and not self.watchdog_tripped and not self.toggle_stale

    @property
    def applied_currents_ua(self) -> tuple[int, int]:
        """The (heave, pitch) currents the outputs apply now, microamperes."""
        return self.commanded_currents_ua if self.outputs_enabled else (0, 0)

    # --- the firmware loop --------------------------------------------------------------------------------------

    def _run(self) -> None:
        while not self._stop.is_set():
            if not self.reading:
                time.sleep(0.001)
                continue
            try:
                readable, _, _ = select.select([self.fd], [], [], 0.001)
                data = os.read(self.fd, 4096) if readable else b""
            except OSError:
                # no host attached to the slave end (EIO): a real board would just wait
                time.sleep(0.001)
                data = b""
            with self.lock:
                for byte in data:
                    if byte == 0:
                        if self._buffer:
                            self._handle_candidate(bytes(self._buffer))
                        self._buffer.clear()
                    else:
                        self._buffer.append(byte)
                        if len(self._buffer) > 300:
                            self._buffer.clear()
                            self.rx_error_count += 1
                self._watchdog()

    def _watchdog(self) -> None:
        now = time.monotonic()
        if self.enable_requested and now - self.last_command_time > self.command_timeout_ms / 1000:
            self.enable_requested = False
            self.watchdog_tripped = True
            self.commanded_currents_ua = (0, 0)

    def _handle_candidate(self, encoded: bytes) -> None:
        body = _unstuff(encoded)
        if body is None or len(body) < 6 or _crc16_bitwise(body[:-2]) != struct.unpack("<H", body[-2:])[0]:
            self.rx_error_count += 1
            return
        message_type, sequence, length = struct.unpack("<BHB", body[:4])
        payload = body[4:-2]
        sizes = {_HELLO: 1, _COMMAND: 9, _STATE_REQUEST: 0}
        if length != len(payload) or sizes.get(message_type) != length:
            self.rx_error_count += 1
            return
        if message_type == _HELLO:
            reply = struct.pack("<HBBHH", sequence, self.protocol_version, self.counter_bits,
                                self.command_timeout_ms, self.toggle_timeout_ms)
            self._reply(_HELLO_REPLY, reply)
        elif message_type == _COMMAND:
            heave_ua, pitch_ua, flags = struct.unpack("<iiB", payload)
            self._command(sequence, heave_ua, pitch_ua, flags)
        else:
            self._state(sequence)

    def _command(self, sequence: int, heave_ua: int, pitch_ua: int, flags: int) -> None:
        now = time.monotonic()
        self.commands.append((sequence, heave_ua, pitch_ua, flags))
        self.last_command_sequence = sequence
        self.last_command_time = now
        if flags & _CLEAR_WATCHDOG:
            self.watchdog_tripped = False
        phase = flags & _TOGGLE
        if phase != self.last_toggle_phase:
            self.last_toggle_phase = phase
            self.last_toggle_time = now
        self.enable_requested = bool(flags & _ENABLE)
        self.commanded_currents_ua = (heave_ua, pitch_ua)

    def _state(self, request_sequence: int) -> None:
        self.state_requests += 1
        status = 0
        if self.outputs_enabled:
            status |= _OUTPUTS_ENABLED
        if self.watchdog_tripped:
            status |= _WATCHDOG_TRIPPED
        if self.toggle_stale:
            status |= _TOGGLE_STALE
        device_time_us = int((time.monotonic() - self._start_time) * 1e6) & 0xFFFFFFFF
        modulus = 1 << self.counter_bits
        counts = [count % modulus for count in self.counts]
        heave_ua, pitch_ua = self.applied_currents_ua
        payload = struct.pack("<HHIIIIIiiHH", request_sequence, self.last_command_sequence, device_time_us,
                              *counts, heave_ua, pitch_ua, status, self.rx_error_count & 0xFFFF)
        self._reply(_STATE, payload)

    def _reply(self, message_type: int, payload: bytes) -> None:
        if self.muted:
            return
        body = struct.pack("<BHB", message_type, self.sequence, len(payload)) + payload
        self.sequence = (self.sequence + 1) & 0xFFFF
        crc = _crc16_bitwise(body)
        if self.corrupt_next_reply_crc:
            crc ^= 0x0100
            self.corrupt_next_reply_crc = False
        frame = b"\x00" + _stuff(body + struct.pack("<H", crc)) + b"\x00"
        prefix = self.garbage_before_next_reply
        self.garbage_before_next_reply = b""
        if self.truncated_frame_before_next_reply:
            prefix += frame[:len(frame) // 2]  # cut mid-frame: no closing delimiter
            self.truncated_frame_before_next_reply = False
        if self.delay_next_reply_s:
            time.sleep(self.delay_next_reply_s)
            self.delay_next_reply_s = 0.0
        self._write(prefix + frame)

    def _write(self, data: bytes) -> None:
        chunks = max(1, self.reply_chunks)
        size = -(-len(data) // chunks)
        for index in range(0, len(data), size):
            if index and self.reply_chunk_delay_s:
                time.sleep(self.reply_chunk_delay_s)
            try:
                os.write(self.fd, data[index:index + size])
            except OSError:
                return  # host side closed: the bytes are lost, as on a real unplugged cable

    def _close_fd(self) -> None:
        fd, self.fd = self.fd, -1
        if fd >= 0:
            try:
                os.close(fd)
            except OSError:
                pass


class PtyRig:
    """A pty pair behind a stable symlink ``link``, a FakeSerialFirmware on the master end.

    It is the serial port a SerialDevice (or bridge_node with backend serial) opens by the link's name.
    ``plug_in()`` again after the firmware disconnected is a board re-enumerating behind the same name.
    """

    def __init__(self, link: Path, counts: Sequence[int] = (0, 0, 0, 0), **firmware_options: Any) -> None:
        self.link = Path(link)
        self.counts = list(counts)
        self.firmware_options = firmware_options
        self.slave_fds: list[int] = []
        self.firmware: FakeSerialFirmware   # set by plug_in()
        self.plug_in()

    def plug_in(self) -> FakeSerialFirmware:
        """Open a new pty behind the link and start firmware on it; the firmware."""
        master_fd, slave_fd = os.openpty()
        tty.setraw(slave_fd)  # no echo or line editing before the host opens the port
        self.slave_fds.append(slave_fd)  # held open so the master side never sees a hang-up of its own
        if self.link.is_symlink():
            self.link.unlink()
        self.link.symlink_to(os.ttyname(slave_fd))
        self.firmware = FakeSerialFirmware(master_fd, **self.firmware_options).start()
        self.firmware.counts = list(self.counts)
        return self.firmware

    def close(self) -> None:
        """Stop the firmware and close the pty ends held open."""
        self.firmware.stop()
        for fd in self.slave_fds:
            os.close(fd)
        self.slave_fds.clear()
