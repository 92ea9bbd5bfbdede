"""The serial link between the bridge (host) and the rig's microcontroller (device), protocol version 1.

This docstring is the specification: firmware written from it alone must interoperate with
``serial_backend.SerialDevice``. The device is a microcontroller with four hardware quadrature decoders
(hub, rail, heave, pitch) and two current-mode amplifier outputs (heave, pitch) plus an amplifier-enable pin,
reached over a USB CDC (virtual COM port) or UART link, 8 data bits, no parity, 1 stop bit, no flow control
(the baud rate is whatever both ends are set to; USB CDC ignores it).

Framing
-------
Every message is one *frame* on the wire::

    0x00 | COBS( body ) | 0x00                  body = header | payload | crc
    header  = type (uint8) | sequence (uint16) | payload_length (uint8)
    crc     = CRC-16 of header | payload (uint16)

- All multi-byte integers are little-endian, the CRC included.
- COBS is Consistent Overhead Byte Stuffing (Cheshire & Baker, IEEE/ACM Trans. Networking 7(2), 1999): the
  encoded body contains no 0x00 byte, so 0x00 marks frame boundaries only and payload bytes can never fake one.
  Encoding: split body at every 0x00 into blocks; each block becomes (len(block) + 1) followed by its bytes; a
  block of 254 non-zero bytes is written as 0xFF + 254 bytes and is not followed by an implied zero (and, if
  the body ends there, by no further block). Examples: ``11 22 00 33`` -> ``03 11 22 02 33``,
  ``00`` -> ``01 01``, 254 bytes ``01..FE`` -> ``FF 01..FE``. An empty body encodes as ``01``.
- A sender writes a 0x00 both before and after each frame. A receiver collects bytes up to each 0x00; an empty
  collection (two delimiters in a row) is ignored, anything else is one frame candidate. The leading 0x00 makes
  a receiver that started mid-frame, or saw line noise, resynchronise at the very next frame, losing at most the
  damaged one.
- CRC-16/CCITT-FALSE (a.k.a. CRC-16/IBM-3740): polynomial 0x1021, initial value 0xFFFF, input and output not
  reflected, final XOR 0x0000; its check value (CRC of the ASCII bytes ``123456789``) is 0x29B1.
- A candidate is rejected (and counted as a receive error, never acted on) when: COBS decoding fails, the
  decoded body is shorter than 6 bytes, the CRC does not match, ``payload_length`` differs from the actual
  payload length, or more than MAX_ENCODED_BYTES arrive without a delimiter (then everything up to the next
  0x00 is discarded). A well-formed frame of an unknown type, or whose payload length does not match its
  type's size below, is also rejected and counted.
- ``sequence`` is the sender's own frame counter, +1 per frame sent, modulo 2**16. The host and the device keep
  independent counters.

Messages (payload layouts as Python ``struct`` formats, little-endian)
--------------------------------------------------------------------
========  ==============  ============  ==================================================================
type      name            direction     payload
========  ==============  ============  ==================================================================
0x01      HELLO           host->device  ``<B`` protocol_version (1). Device replies HELLO_REPLY.
0x81      HELLO_REPLY     device->host  ``<HBBHH`` request_sequence (the HELLO's sequence),
                                        protocol_version, counter_bits (1..32: the counters wrap modulo
                                        2**counter_bits), command_timeout_ms, toggle_timeout_ms
0x02      COMMAND         host->device  ``<iiB`` heave_current_ua, pitch_current_ua (int32, microamperes,
                                        signed: positive drives the joint angle positive), flags. No reply.
0x03      STATE_REQUEST   host->device  empty. Device replies STATE.
0x83      STATE           device->host  ``<HHI4IiiHH`` request_sequence (the STATE_REQUEST's sequence),
                                        last_command_sequence (sequence of the last valid COMMAND received),
                                        device_time_us (free-running microsecond clock at the latch, wraps
                                        at 2**32), counts[4] (hub, rail, heave, pitch; uint32, modulo
                                        2**counter_bits), applied_heave_current_ua, applied_pitch_current_ua
                                        (what the amplifiers are being told now: 0 whenever the outputs are
                                        off), status flags (uint16), rx_error_count (uint16, wraps: frames the
                                        device rejected since power-up)
========  ==============  ============  ==================================================================

The device answers each HELLO and each STATE_REQUEST with exactly one reply, in the order received, and sends
nothing unsolicited. It latches the four counters at the same instant, on receipt of the STATE_REQUEST.
The host matches a reply to its request by ``request_sequence`` and discards replies to earlier requests.

COMMAND flags: bit 0 ENABLE (the host wants the amplifiers on), bit 1 ENABLE_TOGGLE (the enable line's
charge-pump phase: the host flips it once per control period), bit 2 CLEAR_WATCHDOG (clear a latched command
watchdog trip). Other bits are reserved, sent as 0, ignored by the device.

STATE status flags: bit 0 OUTPUTS_ENABLED (the amplifier-enable pin is driven on now), bit 1 WATCHDOG_TRIPPED
(latched command-watchdog trip), bit 2 TOGGLE_STALE (ENABLE requested but ENABLE_TOGGLE stopped changing),
bit 3 AMPLIFIER_FAULT (the amplifiers' fault input, if wired), bit 4 ENCODER_FAULT (a decoder reports an
error, if the hardware can tell). Other bits reserved, 0.

Device behaviour (the firmware's safety duties)
-----------------------------------------------
- On a valid COMMAND: record its sequence and arrival time; if CLEAR_WATCHDOG is set, clear the watchdog
  latch; if ENABLE_TOGGLE differs from the previous COMMAND's, record the time as the last toggle; store ENABLE
  and the two currents.
- The outputs are on (enable pin on, currents as commanded) exactly when: ENABLE is set in the last COMMAND,
  the watchdog is not tripped, and the last toggle is at most toggle_timeout_ms old. Otherwise both current
  outputs are zero and the enable pin is off. TOGGLE_STALE is not latched: toggling again turns the outputs
  back on (as a hardware charge pump would).
- Command watchdog: while ENABLE is set, if no valid COMMAND arrives for command_timeout_ms, the device zeroes
  both currents, turns the enable pin off, clears ENABLE and sets WATCHDOG_TRIPPED, which stays set until a
  COMMAND with CLEAR_WATCHDOG arrives. STATE_REQUESTs do not feed the watchdog. Defaults:
  command_timeout_ms = 50 and toggle_timeout_ms = 50 (6 periods of the paper's 8 ms loop); the device
  reports its values in HELLO_REPLY.
- At power-up and after any reset: outputs off, currents zero, ENABLE clear, WATCHDOG_TRIPPED clear.

Host sequence per control period (what ``SerialDevice`` sends): STATE_REQUEST and wait for STATE
(read_counters), COMMAND (write_currents), COMMAND with the toggle flipped (toggle_enable): about 20 + 45 + 2x17
bytes, well inside 115200 baud at 8 ms.

This module holds the pure parts: CRC, COBS, frame encoding and decoding, payload layouts, and a stream
decoder that turns arbitrary byte chunks into frames and counts what it rejects.
"""
from __future__ import annotations

import dataclasses
import enum
import struct
from typing import ClassVar

PROTOCOL_VERSION = 1
FRAME_DELIMITER = 0x00

_HEADER = struct.Struct("<BHB")  # type, sequence, payload_length
_CRC = struct.Struct("<H")
HEADER_BYTES = _HEADER.size
CRC_BYTES = _CRC.size
MAX_PAYLOAD_BYTES = 64
#: longest COBS-encoded body a receiver accepts (body plus COBS overhead: one byte per 254 and one more)
MAX_ENCODED_BYTES = HEADER_BYTES + MAX_PAYLOAD_BYTES + CRC_BYTES + 2

SEQUENCE_MODULUS = 1 << 16
INT32_MIN, INT32_MAX = -(1 << 31), (1 << 31) - 1


class ProtocolError(ValueError):
    """A frame or payload that does not follow the specification above."""


class MessageType(enum.IntEnum):
    """A frame's type byte (the messages table above)."""

    HELLO = 0x01
    COMMAND = 0x02
    STATE_REQUEST = 0x03
    HELLO_REPLY = 0x81
    STATE = 0x83


class CommandFlags(enum.IntFlag):
    """COMMAND flag bits (see COMMAND flags above)."""

    ENABLE = 0x01
    ENABLE_TOGGLE = 0x02
    CLEAR_WATCHDOG = 0x04


class StatusFlags(enum.IntFlag):
    """STATE status bits (see STATE status flags above)."""

    OUTPUTS_ENABLED = 0x0001
    WATCHDOG_TRIPPED = 0x0002
    TOGGLE_STALE = 0x0004
    AMPLIFIER_FAULT = 0x0008
    ENCODER_FAULT = 0x0010


# --- CRC-16/CCITT-FALSE ----------------------------------------------------------------------------------------

def _crc_table() -> tuple[int, ...]:
    table = []
    for byte in range(256):
        crc = byte << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) if crc & 0x8000 else (crc << 1)
        table.append(crc & 0xFFFF)
    return tuple(table)


_CRC_TABLE = _crc_table()
CRC_CHECK_VALUE = 0x29B1  # crc16_ccitt_false(b"123456789")


def crc16_ccitt_false(data: bytes, crc: int = 0xFFFF) -> int:
    """CRC-16/CCITT-FALSE: poly 0x1021, init 0xFFFF, no reflection, no final XOR (check value 0x29B1)."""
    for byte in data:
        crc = ((crc << 8) & 0xFFFF) ^ _CRC_TABLE[(crc >> 8) ^ byte]
    return crc


# --- COBS ------------------------------------------------------------------------------------------------------

def cobs_encode(data: bytes) -> bytes:
    """Consistent Overhead Byte Stuffing: the result has no 0x00 byte and is at most len(data)/254 + 1 longer.

    Canonical form (as Cheshire & Baker's reference code): a body ending in a full 254-byte block gets no
    trailing empty block.
    """
    out = bytearray(b"\x00")
    code_index, code = 0, 1
    last = len(data) - 1
    for position, byte in enumerate(data):
        if byte:
            out.append(byte)
            code += 1
        if not byte or code == 0xFF:  # a zero ends the block; so does a full block of 254 non-zero bytes
            out[code_index] = code
            code = 1
            if not byte or position < last:
                code_index = len(out)
                out.append(0)
            else:
                return bytes(out)
    out[code_index] = code
    return bytes(out)


def cobs_decode(encoded: bytes) -> bytes:
    """Inverse of cobs_encode. Raises ProtocolError on a 0x00 byte or a block running past the end."""
    out = bytearray()
    index, length = 0, len(encoded)
    while index < length:
        code = encoded[index]
        if code == 0:
            raise ProtocolError(f"COBS: zero byte at offset {index}")
        end = index + code
        if end > length:
            raise ProtocolError(f"COBS: block of {code - 1} bytes at offset {index} runs past the end ({length})")
        block = encoded[index + 1:end]
        if 0 in block:
            raise ProtocolError("COBS: zero byte inside a block")
        out += block
        index = end
        if code != 0xFF and index < length:
            out.append(0)
    return bytes(out)


# --- frames ----------------------------------------------------------------------------------------------------

@dataclasses.dataclass(frozen=True)
class Frame:
    """One decoded frame: its type (a MessageType value, or another int if unknown), sequence, payload."""

    type: int
    sequence: int
    payload: bytes


def encode_frame(message_type: int, sequence: int, payload: bytes = b"") -> bytes:
    """The bytes to write: 0x00 | COBS(header | payload | CRC) | 0x00."""
    if len(payload) > MAX_PAYLOAD_BYTES:
        raise ProtocolError(f"payload of {len(payload)} bytes exceeds {MAX_PAYLOAD_BYTES}")
    body = _HEADER.pack(message_type, sequence % SEQUENCE_MODULUS, len(payload)) + payload
    body += _CRC.pack(crc16_ccitt_false(body))
    return b"\x00" + cobs_encode(body) + b"\x00"


def decode_body(encoded: bytes) -> Frame:
    """One frame from the bytes between two delimiters. Raises ProtocolError (reason in the message)."""
    if len(encoded) > MAX_ENCODED_BYTES:
        raise ProtocolError(f"oversize: {len(encoded)} bytes without a delimiter")
    body = cobs_decode(encoded)
    if len(body) < HEADER_BYTES + CRC_BYTES:
        raise ProtocolError(f"short: {len(body)} bytes, a frame has at least {HEADER_BYTES + CRC_BYTES}")
    (received_crc,) = _CRC.unpack_from(body, len(body) - CRC_BYTES)
    computed_crc = crc16_ccitt_false(body[:-CRC_BYTES])
    if received_crc != computed_crc:
        raise ProtocolError(f"CRC mismatch: received 0x{received_crc:04X}, computed 0x{computed_crc:04X}")
    message_type, sequence, payload_length = _HEADER.unpack_from(body)
    payload = body[HEADER_BYTES:-CRC_BYTES]
    if payload_length != len(payload):
        raise ProtocolError(f"length: header says {payload_length} payload bytes, frame has {len(payload)}")
    return Frame(message_type, sequence, payload)


def decode_frame(wire: bytes) -> Frame:
    """One frame from its wire bytes (delimiters optional)."""
    return decode_body(wire.strip(b"\x00"))


class FrameDecoder:
    """Stream decoder: feed it byte chunks as they arrive (any split, any garbage), get whole valid frames.

    Rejected candidates are counted by reason (``cobs_errors``, ``short_errors``, ``crc_errors``,
    ``length_errors``, ``oversize_errors``; ``error_count`` is their sum) and never returned. Frame types and
    payload sizes are checked one layer up (``parse_payload``).
    """

    def __init__(self) -> None:
        self._buffer = bytearray()
        self._discarding = False  # an oversize candidate: drop bytes until the next delimiter
        # counts since construction: frames passed, and frames rejected by each check
        self.frames_ok = 0
        self.cobs_errors = self.short_errors = self.crc_errors = self.length_errors = self.oversize_errors = 0

    @property
    def error_count(self) -> int:
        """Frames rejected so far, all checks together."""
        return self.cobs_errors + self.short_errors + self.crc_errors + self.length_errors + self.oversize_errors

    def reset(self) -> None:
        """Drop a partly received frame (after reopening the port)."""
        self._buffer.clear()
        self._discarding = False

    def feed(self, data: bytes) -> list[Frame]:
        """The complete frames in a chunk of received bytes; a partial frame waits for the next chunk."""
        frames: list[Frame] = []
        start = 0
        while True:
            end = data.find(b"\x00", start)
            self._collect(data[start:] if end < 0 else data[start:end])
            if end < 0:
                return frames
            frame = self._end_of_candidate()
            if frame is not None:
                frames.append(frame)
            start = end + 1

    def _collect(self, chunk: bytes) -> None:
        if self._discarding or not chunk:
            return
        self._buffer += chunk
        if len(self._buffer) > MAX_ENCODED_BYTES:
            self.oversize_errors += 1
            self._buffer.clear()
            self._discarding = True

    def _end_of_candidate(self) -> Frame | None:
        if self._discarding:
            self._discarding = False
            return None
        if not self._buffer:
            return None
        candidate = bytes(self._buffer)
        self._buffer.clear()
        try:
            frame = decode_body(candidate)
        except ProtocolError as error:
            reason = str(error).split(":", 1)[0]
            if reason == "CRC mismatch":
                self.crc_errors += 1
            elif reason == "short":
                self.short_errors += 1
            elif reason == "length":
                self.length_errors += 1
            else:
                self.cobs_errors += 1
            return None
        self.frames_ok += 1
        return frame


# --- payloads ---------------------------------------------------------------------------------------------------

@dataclasses.dataclass(frozen=True)
class _Payload:
    """A message's payload: its fields, in declaration order, are the values of its LAYOUT.

    A tuple field gives one value per item, as parse_payload reads them back.
    """

    LAYOUT: ClassVar[struct.Struct]

    def pack(self) -> bytes:
        values: list[int] = []
        for field in dataclasses.fields(self):
            value = getattr(self, field.name)
            values.extend(value if isinstance(value, tuple) else (value,))
        return self.LAYOUT.pack(*values)


@dataclasses.dataclass(frozen=True)
class Hello(_Payload):
    """HELLO: the protocol version the host speaks."""

    LAYOUT = struct.Struct("<B")
    protocol_version: int = PROTOCOL_VERSION


@dataclasses.dataclass(frozen=True)
class Command(_Payload):
    """COMMAND: the (heave, pitch) currents, microamperes, and the CommandFlags."""

    LAYOUT = struct.Struct("<iiB")
    heave_current_ua: int
    pitch_current_ua: int
    flags: int


@dataclasses.dataclass(frozen=True)
class StateRequest(_Payload):
    """STATE_REQUEST: no fields."""

    LAYOUT = struct.Struct("<")


@dataclasses.dataclass(frozen=True)
class HelloReply(_Payload):
    """HELLO_REPLY: the device's protocol version, counter width (bits) and timeouts, ms.

    request_sequence is the HELLO's sequence; the counters wrap modulo 2**counter_bits.
    """

    LAYOUT = struct.Struct("<HBBHH")
    request_sequence: int
    protocol_version: int
    counter_bits: int
    command_timeout_ms: int
    toggle_timeout_ms: int


@dataclasses.dataclass(frozen=True)
class State(_Payload):
    """STATE: the latched counters, the applied currents (microamperes), StatusFlags and errors.

    request_sequence is the STATE_REQUEST's sequence, last_command_sequence the last valid COMMAND's; device_time_us
    is the device's microsecond clock at the latch, and rx_error_count the frames it rejected since power-up.
    """

    LAYOUT = struct.Struct("<HHI4IiiHH")
    request_sequence: int
    last_command_sequence: int
    device_time_us: int
    counts: tuple[int, int, int, int]
    applied_heave_current_ua: int
    applied_pitch_current_ua: int
    status: int
    rx_error_count: int


PAYLOAD_CLASSES: dict[MessageType, type[Hello | HelloReply | Command | StateRequest | State]] = {
    MessageType.HELLO: Hello,
    MessageType.HELLO_REPLY: HelloReply,
    MessageType.COMMAND: Command,
    MessageType.STATE_REQUEST: StateRequest,
    MessageType.STATE: State,
}


def parse_payload(frame: Frame) -> Hello | HelloReply | Command | StateRequest | State:
    """The typed payload of a valid frame. Raises ProtocolError for an unknown type or a wrong payload size."""
    try:
        cls = PAYLOAD_CLASSES[MessageType(frame.type)]
    except ValueError:
        raise ProtocolError(f"unknown message type 0x{frame.type:02X}") from None
    if len(frame.payload) != cls.LAYOUT.size:
        raise ProtocolError(f"{cls.__name__} payload is {cls.LAYOUT.size} bytes, got {len(frame.payload)}")
    fields = cls.LAYOUT.unpack(frame.payload)
    if cls is State:
        return State(fields[0], fields[1], fields[2], tuple(fields[3:7]), *fields[7:])
    return cls(*fields)


_MESSAGE_TYPES = {cls: message_type for message_type, cls in PAYLOAD_CLASSES.items()}


def message_type_of(payload: Hello | HelloReply | Command | StateRequest | State) -> MessageType:
    """The message type of a typed payload."""
    return _MESSAGE_TYPES[type(payload)]


def encode_message(sequence: int, payload: Hello | HelloReply | Command | StateRequest | State) -> bytes:
    """Wire bytes of one typed message."""
    return encode_frame(message_type_of(payload), sequence, payload.pack())
