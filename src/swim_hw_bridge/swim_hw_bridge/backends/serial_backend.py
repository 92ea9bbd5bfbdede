"""The ``serial`` backend: a microcontroller with hardware quadrature decoders and current outputs, over USB serial.

The wire protocol (framing, CRC, messages, the device's command watchdog and enable charge pump) is specified in
``serial_protocol``'s docstring. This module is the host side: ``SerialDevice`` implements ``Device`` on top of
pyserial. Per call it does:

- ``read_counters``: send STATE_REQUEST, wait up to ``read_timeout_s`` for the STATE that echoes its sequence
  (replies to older requests, e.g. one that arrived after an earlier timeout, are discarded and counted), and
  return the counters. The device's frame sequence numbers are unwrapped into ``CounterSample.sequence``; a gap
  counts missed replies, a repeat is passed on (the bridge's stale-read check sees it).
- ``write_currents``: send COMMAND (currents in microamperes, the ENABLE flag and the current enable phase).
  No reply; the next STATE's ``last_command_sequence`` tells whether it arrived (mismatches are counted).
- ``toggle_enable``: flip the enable phase and send a COMMAND with the last currents, so the device's charge
  pump sees a toggle every period even if the caller skips a write.
- ``enable``: COMMAND with ENABLE and CLEAR_WATCHDOG (a latched device watchdog trip is cleared only here).
  ``disable``: COMMAND with zero currents and ENABLE clear; it never raises (if the link is down the device
  watchdog zeroes the outputs by itself within command_timeout_ms).

Errors: a port that cannot be opened, a write or read that fails (unplugged cable, closed pseudo-terminal), no
reply within the timeout, a device speaking another protocol version or counter width, and a device that
reports its command watchdog tripped or its outputs off while the host has them enabled are all ``DeviceError``.
After a failure the port is closed; **reconnecting is calling open() again** (the bridge's configure step does),
which reopens the port by name and repeats the HELLO handshake. A stable name such as
/dev/serial/by-id/usb-... survives the USB re-enumeration after an unplug.
"""
from __future__ import annotations

import math
import os
import select
import time
from typing import Any, cast

import serial

from ..device import CounterSample, Device, DeviceError
from . import serial_protocol as protocol
from .serial_protocol import CommandFlags, MessageType, StatusFlags

DEFAULTS: dict[str, Any] = {
    "port": "/dev/ttyACM0",
    "baud_rate": 115200,
    "read_timeout_s": 0.005,
    "write_timeout_s": 0.005,  # counted only while the output buffer is full (see _write)
    "open_timeout_s": 2.0,
    "hello_retry_s": 0.1,
    "poll_s": 0.0005,
    "counter_bits": 32,
}


class SerialDevice(Device):
    """Motors and encoders through the rig's microcontroller over a serial port (protocol: serial_protocol).

    Config keys (plain dict; every key has a default; other keys are ignored):

    - ``port`` (str, "/dev/ttyACM0"): a device path or any pyserial URL (``socket://host:port``, ``rfc2217://``,
      ``loop://``). Prefer a stable /dev/serial/by-id/ path: reconnecting reopens it by name.
    - ``baud_rate`` (int, 115200): UART speed; ignored by USB CDC devices.
    - ``read_timeout_s`` (float, 0.005): longest wait for a STATE reply in read_counters (keep it under the
      control period, 8 ms on the paper's rig).
    - ``write_timeout_s`` (float, 0.005): longest a write may wait for room in a full output buffer (a device
      that stopped reading) before it is a DeviceError.
    - ``open_timeout_s`` (float, 2.0): how long open() keeps sending HELLO (a board may reset when the port
      opens and take a while to boot).
    - ``hello_retry_s`` (float, 0.1): interval between HELLOs during open().
    - ``poll_s`` (float, 0.0005): granularity of the reply wait (one blocking read lasts at most this long).
    - ``counter_bits`` (int, 32): expected counter width; open() refuses a device reporting another.

    Diagnostics (read-only attributes, counts since construction): ``decoder`` (a FrameDecoder: frames_ok and
    rejected frames by reason), ``stale_replies``, ``missed_replies``, ``unacknowledged_commands``,
    ``unexpected_frames``, ``device_rx_errors`` (the device's count of frames it rejected), ``last_state``
    (the last STATE payload), ``device_info`` (the HELLO_REPLY), ``reconnects``.
    """

    def __init__(self, config: dict[str, Any] | None = None) -> None:
        # the bridge passes its whole device_config (conversion values too): take the keys this backend knows
        self.config = {**DEFAULTS, **{key: value for key, value in (config or {}).items() if key in DEFAULTS}}
        self.port_name = str(self.config["port"])
        self.read_timeout_s = float(self.config["read_timeout_s"])
        self.poll_s = float(self.config["poll_s"])
        self.write_timeout_s = float(self.config["write_timeout_s"])
        self.counter_bits = int(self.config["counter_bits"])
        self._port: serial.SerialBase | None = None
        self._fd: int | None = None
        self.decoder = protocol.FrameDecoder()
        self._host_sequence = 0
        self._last_command_sequence: int | None = None
        self._device_sequence: int | None = None  # last STATE frame sequence, modulo 2**16
        self._sample_sequence = 0  # unwrapped device STATE sequence
        self._enabled = False
        self._toggle_phase = False
        self._heave_current_ua = 0
        self._pitch_current_ua = 0
        self.stale_replies = 0
        self.missed_replies = 0
        self.unacknowledged_commands = 0
        self.unexpected_frames = 0
        self.device_rx_errors = 0
        self.reconnects = 0
        self._opened_before = False
        self.last_state: protocol.State | None = None
        self.device_info: protocol.HelloReply | None = None
        self.last_error: str | None = None

    # --- Device interface ---------------------------------------------------------------------------------------

    def open(self) -> None:
        """Open (or reopen) the port, handshake with HELLO, command zero current with the outputs disabled."""
        self._close_port()
        try:
            self._port = serial.serial_for_url(
                self.port_name, baudrate=int(self.config["baud_rate"]), timeout=self.poll_s,
                write_timeout=float(self.config["write_timeout_s"]), exclusive=True)
        except (serial.SerialException, OSError, ValueError) as error:
            self._port = None
            raise DeviceError(f"serial backend: cannot open {self.port_name!r}: {error}. Is the board plugged in, "
                              "is the path right (ls /dev/serial/by-id/), is the user in group dialout, "
                              "does another process hold the port?") from error
        try:
            self._fd = self._port.fileno()
        except (AttributeError, OSError, ValueError, NotImplementedError):
            self._fd = None
        if self._opened_before:
            self.reconnects += 1
        self._opened_before = True
        self.decoder.reset()
        self._device_sequence = None
        self._enabled = False
        self._heave_current_ua = self._pitch_current_ua = 0
        try:
            self._port.reset_input_buffer()
            self._handshake(float(self.config["open_timeout_s"]), float(self.config["hello_retry_s"]))
            self._send_command(0)
        except DeviceError:
            self._close_port()
            raise

    def read_counters(self) -> CounterSample:
        """Send STATE_REQUEST and read the STATE reply's counters; raises DeviceError on failure."""
        request_sequence = self._send(protocol.StateRequest())
        frame = self._await_reply(MessageType.STATE, request_sequence, self.read_timeout_s)
        try:
            state = protocol.parse_payload(frame)
        except protocol.ProtocolError as error:
            self.unexpected_frames += 1
            raise DeviceError(f"serial backend: malformed STATE from {self.port_name!r}: {error} "
                              "(firmware of another protocol version?)") from error
        assert isinstance(state, protocol.State)   # the frame's type is STATE
        self.last_state = state
        self.device_rx_errors = state.rx_error_count
        if self._device_sequence is not None:
            step = (frame.sequence - self._device_sequence) % protocol.SEQUENCE_MODULUS
            self.missed_replies += max(step - 1, 0)
            self._sample_sequence += step
        self._device_sequence = frame.sequence
        if self._last_command_sequence is not None and state.last_command_sequence != self._last_command_sequence:
            self.unacknowledged_commands += 1
        if self._enabled:
            self._check_outputs(state.status)
        modulus = 1 << self.counter_bits
        counts = cast(tuple[int, int, int, int], tuple(count % modulus for count in state.counts))
        return CounterSample(counts=counts, monotonic_s=time.monotonic(), sequence=self._sample_sequence)

    def write_currents(self, heave_a: float, pitch_a: float) -> None:
        """Send the (heave, pitch) currents, A, as microamperes; a non-finite one sends zero and raises."""
        if not (math.isfinite(heave_a) and math.isfinite(pitch_a)):
            self._heave_current_ua = self._pitch_current_ua = 0
            self._send_command(self._flags())
            raise DeviceError(f"serial backend: non-finite current command ({heave_a}, {pitch_a}) A; sent zero")
        self._heave_current_ua = _microamperes(heave_a)
        self._pitch_current_ua = _microamperes(pitch_a)
        self._send_command(self._flags())

    def toggle_enable(self) -> None:
        """Flip the toggle phase and send a COMMAND with it."""
        self._toggle_phase = not self._toggle_phase
        self._send_command(self._flags())

    def enable(self) -> None:
        """Ask for the amplifiers on, with a fresh toggle and the device watchdog's latch cleared."""
        self._enabled = True
        self._toggle_phase = not self._toggle_phase  # a fresh toggle starts the device's charge-pump window
        self._send_command(self._flags() | CommandFlags.CLEAR_WATCHDOG)

    def disable(self) -> None:
        """Zero the currents and clear ENABLE on the device; never raises (its watchdog zeroes anyway)."""
        self._enabled = False
        self._heave_current_ua = self._pitch_current_ua = 0
        if self._port is None:
            return
        try:
            self._send_command(0)
        except DeviceError as error:
            # nothing more can be done from here: the device watchdog zeroes the outputs on its own
            self.last_error = str(error)

    def close(self) -> None:
        """Disable, then close the port."""
        self.disable()
        self._close_port()

    # --- helpers ------------------------------------------------------------------------------------------------

    @property
    def is_open(self) -> bool:
        """Whether the port is open."""
        return self._port is not None

    def _flags(self) -> int:
        flags = CommandFlags.ENABLE if self._enabled else 0
        if self._toggle_phase:
            flags |= CommandFlags.ENABLE_TOGGLE
        return int(flags)

    def _send_command(self, flags: int) -> None:
        command = protocol.Command(self._heave_current_ua, self._pitch_current_ua, flags)
        self._last_command_sequence = self._send(command)

    def _send(self, payload: protocol.Hello | protocol.Command | protocol.StateRequest) -> int:
        if self._port is None:
            raise DeviceError(f"serial backend: {self.port_name!r} is not open (open() reconnects)")
        sequence = self._host_sequence
        self._host_sequence = (sequence + 1) % protocol.SEQUENCE_MODULUS
        try:
            self._write(protocol.encode_message(sequence, payload))
        except serial.SerialTimeoutException as error:
            self._fail(f"write to {self.port_name!r} blocked longer than {self.write_timeout_s} s "
                       "(device not reading?)", error)
        except (serial.SerialException, OSError) as error:
            self._fail(f"write to {self.port_name!r} failed (device disconnected?)", error)
        return sequence

    def _write(self, data: bytes) -> None:
        """Write all of data, waiting at most write_timeout_s for room in the output buffer.

        Why not pyserial's write(): with a write timeout it starts the clock before os.write and raises once the
        clock has run out even when everything was written, so a thread switch (the interpreter's switch interval
        is 5 ms) turns a complete write into a false timeout. This writes to the non-blocking descriptor that
        pyserial opened and only waits, with the timeout, when the kernel buffer is actually full.
        """
        assert self._port is not None   # called on an open port only
        if self._fd is None:  # a URL handler without a descriptor
            self._port.write(data)
            return
        view = memoryview(data)
        deadline = None
        while view:
            try:
                written = os.write(self._fd, view)
            except BlockingIOError:
                written = 0
            view = view[written:]
            if view:
                now = time.monotonic()
                deadline = deadline if deadline is not None else now + self.write_timeout_s
                if now >= deadline or not select.select([], [self._fd], [], deadline - now)[1]:
                    raise serial.SerialTimeoutException("Write timeout")

    def _await_reply(self, message_type: MessageType, request_sequence: int, timeout_s: float) -> protocol.Frame:
        assert self._port is not None   # called on an open port only
        deadline = time.monotonic() + timeout_s
        while True:
            try:
                data = self._port.read(self._port.in_waiting or 1)
            except (serial.SerialException, OSError) as error:
                self._fail(f"read from {self.port_name!r} failed (device disconnected?)", error)
            for frame in self.decoder.feed(data):
                if frame.type == message_type and len(frame.payload) >= 2 \
                        and int.from_bytes(frame.payload[:2], "little") == request_sequence:
                    return frame
                if frame.type in (MessageType.STATE, MessageType.HELLO_REPLY):
                    self.stale_replies += 1
                else:
                    self.unexpected_frames += 1
            if time.monotonic() >= deadline:
                # the port stays open: a late reply is recognised as stale by the next request
                raise DeviceError(
                    f"serial backend: no {message_type.name} reply to request {request_sequence} from "
                    f"{self.port_name!r} within {timeout_s} s (rejected frames so far: {self.decoder.error_count}, "
                    f"of which CRC {self.decoder.crc_errors})")

    def _handshake(self, timeout_s: float, retry_s: float) -> None:
        deadline = time.monotonic() + timeout_s
        while True:
            request_sequence = self._send(protocol.Hello())
            try:
                frame = self._await_reply(MessageType.HELLO_REPLY, request_sequence,
                                          min(retry_s, max(deadline - time.monotonic(), 0.0)))
                break
            except DeviceError:
                if time.monotonic() >= deadline:
                    raise DeviceError(f"serial backend: no HELLO_REPLY from {self.port_name!r} within {timeout_s} s; "
                                      "is the firmware running and speaking the swim serial protocol "
                                      f"(version {protocol.PROTOCOL_VERSION}) at {self.config['baud_rate']} baud?")
        try:
            info = protocol.parse_payload(frame)
        except protocol.ProtocolError as error:
            raise DeviceError(f"serial backend: malformed HELLO_REPLY from {self.port_name!r}: {error}") from error
        assert isinstance(info, protocol.HelloReply)   # the frame's type is HELLO_REPLY
        if info.protocol_version != protocol.PROTOCOL_VERSION:
            raise DeviceError(f"serial backend: device speaks protocol version {info.protocol_version}, this host "
                              f"{protocol.PROTOCOL_VERSION}; update the firmware or the bridge")
        if info.counter_bits != self.counter_bits:
            raise DeviceError(f"serial backend: device counters are {info.counter_bits} bits, config counter_bits "
                              f"is {self.counter_bits}; set counter_bits: {info.counter_bits}")
        self.device_info = info

    def _check_outputs(self, status: int) -> None:
        assert self.device_info is not None   # set by the handshake of open()
        if status & StatusFlags.WATCHDOG_TRIPPED:
            self._enabled = False
            raise DeviceError(f"serial backend: device command watchdog tripped (no valid COMMAND for "
                              f"{self.device_info.command_timeout_ms} ms): currents zeroed, amplifiers off; "
                              "disable() and enable() to resume")
        if status & StatusFlags.TOGGLE_STALE:
            raise DeviceError(f"serial backend: device saw no enable toggle for {self.device_info.toggle_timeout_ms} "
                              "ms: amplifiers off (toggle_enable must be called every period)")
        if status & StatusFlags.AMPLIFIER_FAULT:
            raise DeviceError("serial backend: device reports an amplifier fault (check the amplifiers' fault LEDs)")
        if status & StatusFlags.ENCODER_FAULT:
            raise DeviceError("serial backend: device reports an encoder fault (check the encoder cables)")

    def _fail(self, what: str, error: Exception) -> None:
        self._close_port()
        self._enabled = False
        self.last_error = f"serial backend: {what}: {error}"
        raise DeviceError(self.last_error + "; open() reconnects") from error

    def _close_port(self) -> None:
        port, self._port, self._fd = self._port, None, None
        if port is not None:
            try:
                port.close()
            except (serial.SerialException, OSError):
                pass  # the port is gone already (unplugged): nothing left to release


def _microamperes(current_a: float) -> int:
    """Amperes to the protocol's int32 microamperes, clamped to the int32 range (the caller has saturated)."""
    return min(max(round(current_a * 1e6), protocol.INT32_MIN), protocol.INT32_MAX)
