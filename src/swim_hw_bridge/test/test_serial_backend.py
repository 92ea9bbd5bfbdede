"""The serial backend end to end: SerialDevice over a pseudo-terminal pair against an emulated firmware thread.

The firmware (testing/fake_serial_firmware.py, an emulation) is written from the protocol specification
independently of serial_protocol.py, so these exchanges check both sides against the spec, not against each other.
"""
from __future__ import annotations

import time

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from swim_hw_bridge.backends import serial_protocol as protocol
from swim_hw_bridge.backends.serial_backend import SerialDevice
from swim_hw_bridge.device import DeviceError
from swim_hw_bridge.testing import fake_serial_firmware as fake
from swim_hw_bridge.testing.fake_serial_firmware import PtyRig

COUNTS = (1, 2**32 - 1, 123_456_789, 2**31)  # distinct per channel, both ends of the uint32 range


@pytest.fixture
def rig(tmp_path):
    rig = PtyRig(tmp_path / "ttyRIG", COUNTS)
    yield rig
    rig.close()


@pytest.fixture
def device(rig):
    device = SerialDevice({"port": str(rig.link), "read_timeout_s": 0.2, "open_timeout_s": 1.0})
    device.open()
    yield device
    device.close()


def wait_until(condition, timeout_s: float = 1.0) -> bool:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if condition():
            return True
        time.sleep(0.002)
    return condition()


# --- pure protocol parts ---------------------------------------------------------------------------------------

def test_crc_check_value():
    assert protocol.crc16_ccitt_false(b"123456789") == protocol.CRC_CHECK_VALUE == 0x29B1
    assert fake._crc16_bitwise(b"123456789") == 0x29B1


@pytest.mark.parametrize("data, encoded", [  # Cheshire & Baker's scheme, the examples on Wikipedia's COBS page
    (b"", b"\x01"),
    (b"\x00", b"\x01\x01"),
    (b"\x00\x00", b"\x01\x01\x01"),
    (b"\x11\x22\x00\x33", b"\x03\x11\x22\x02\x33"),
    (b"\x11\x22\x33\x44", b"\x05\x11\x22\x33\x44"),
    (b"\x11\x00\x00\x00", b"\x02\x11\x01\x01\x01"),
    (bytes(range(1, 255)), b"\xff" + bytes(range(1, 255))),
    (bytes(range(0, 255)), b"\x01\xff" + bytes(range(1, 255))),
    (bytes(range(1, 256)), b"\xff" + bytes(range(1, 255)) + b"\x02\xff"),
])
def test_cobs_known_vectors(data, encoded):
    assert protocol.cobs_encode(data) == encoded
    assert protocol.cobs_decode(encoded) == data
    assert fake._stuff(data) == encoded


@settings(max_examples=300, deadline=None)
@given(st.binary(max_size=700))
def test_cobs_round_trip(data):
    encoded = protocol.cobs_encode(data)
    assert 0 not in encoded
    assert len(encoded) <= len(data) + len(data) // 254 + 1
    assert protocol.cobs_decode(encoded) == data
    assert fake._unstuff(encoded) == data


@settings(max_examples=300, deadline=None)
@given(st.integers(0, 255), st.integers(0, 2**16 - 1), st.binary(max_size=protocol.MAX_PAYLOAD_BYTES))
def test_frame_round_trip(message_type, sequence, payload):
    wire = protocol.encode_frame(message_type, sequence, payload)
    assert wire[0] == 0 and wire[-1] == 0 and 0 not in wire[1:-1]
    assert protocol.decode_frame(wire) == protocol.Frame(message_type, sequence, payload)


@settings(max_examples=200, deadline=None)
@given(st.integers(-2**31, 2**31 - 1), st.integers(-2**31, 2**31 - 1), st.integers(0, 7),
       st.lists(st.integers(0, 2**32 - 1), min_size=4, max_size=4), st.integers(0, 2**16 - 1))
def test_message_round_trip(heave_ua, pitch_ua, flags, counts, sequence):
    command = protocol.Command(heave_ua, pitch_ua, flags)
    assert protocol.parse_payload(protocol.decode_frame(protocol.encode_message(sequence, command))) == command
    state = protocol.State(sequence, 7, 123, tuple(counts), heave_ua, pitch_ua, 0x3, 9)
    assert protocol.parse_payload(protocol.decode_frame(protocol.encode_message(sequence, state))) == state


@settings(max_examples=200, deadline=None)
@given(st.lists(st.binary(max_size=protocol.MAX_PAYLOAD_BYTES), min_size=1, max_size=6),
       st.lists(st.binary(max_size=40), min_size=7, max_size=7), st.data())
def test_stream_decoder_resyncs_through_garbage_and_any_split(payloads, garbage, data):
    """Frames separated by random garbage (zeros included), fed in random chunks: every frame comes out, in order."""
    stream = bytearray(garbage[0])
    for index, payload in enumerate(payloads):
        stream += protocol.encode_frame(protocol.MessageType.STATE, index, payload) + garbage[index + 1]
    cuts = sorted(data.draw(st.lists(st.integers(0, len(stream)), max_size=20)))
    decoder = protocol.FrameDecoder()
    frames = []
    for start, end in zip([0, *cuts], [*cuts, len(stream)]):
        frames += decoder.feed(bytes(stream[start:end]))
    assert [(frame.sequence, frame.payload) for frame in frames] == list(enumerate(payloads))


def test_decoder_counts_each_kind_of_malformed_frame():
    good = protocol.encode_frame(protocol.MessageType.STATE, 1, b"abc")
    body = protocol.cobs_decode(good[1:-1])
    bad_crc = b"\x00" + protocol.cobs_encode(body[:-1] + bytes([body[-1] ^ 1])) + b"\x00"
    lying_length = body[:3] + b"\x05" + body[4:-2]
    lying_length += protocol.crc16_ccitt_false(lying_length).to_bytes(2, "little")
    short = b"\x00" + protocol.cobs_encode(b"\x01\x02\x03") + b"\x00"
    block_past_end = b"\x00\x05\x01\x02\x00"
    oversize = b"\x07" * 200
    truncated = good[:-3]  # cut before its last bytes and closing delimiter; the next frame's 0x00 ends it
    decoder = protocol.FrameDecoder()
    frames = decoder.feed(bad_crc + block_past_end + truncated + short + oversize + good
                          + b"\x00" + protocol.cobs_encode(lying_length) + b"\x00" + good)
    assert frames == [protocol.Frame(protocol.MessageType.STATE, 1, b"abc")] * 2
    assert decoder.frames_ok == 2
    assert decoder.crc_errors >= 1 and decoder.cobs_errors >= 1 and decoder.short_errors >= 1
    assert decoder.oversize_errors == 1
    assert decoder.length_errors == 1
    assert decoder.error_count == 6
    with pytest.raises(protocol.ProtocolError, match="payload is 9 bytes"):
        protocol.parse_payload(protocol.Frame(protocol.MessageType.COMMAND, 0, b"\x00" * 8))
    with pytest.raises(protocol.ProtocolError, match="unknown message type"):
        protocol.parse_payload(protocol.Frame(0x42, 0, b""))


# --- end to end over a pseudo-terminal ----------------------------------------------------------------------------

def test_counters_and_currents_round_trip(rig, device):
    assert device.device_info.command_timeout_ms == 50
    first = device.read_counters()
    assert first.counts == COUNTS
    assert rig.firmware.applied_currents_ua == (0, 0) and not rig.firmware.outputs_enabled  # open(): zero, off
    device.enable()
    device.write_currents(1.5, -0.75)
    device.toggle_enable()
    rig.firmware.counts = [5, 6, 7, 8]
    second = device.read_counters()
    assert second.counts == (5, 6, 7, 8)
    assert second.sequence == first.sequence + 1
    assert second.monotonic_s > first.monotonic_s
    assert rig.firmware.applied_currents_ua == (1_500_000, -750_000)
    assert rig.firmware.outputs_enabled
    assert device.last_state.applied_heave_current_ua == 1_500_000
    assert device.last_state.applied_pitch_current_ua == -750_000
    assert device.last_state.status & protocol.StatusFlags.OUTPUTS_ENABLED
    assert device.unacknowledged_commands == 0 and device.decoder.error_count == 0
    device.disable()
    device.read_counters()
    assert rig.firmware.applied_currents_ua == (0, 0) and not rig.firmware.outputs_enabled


def test_toggle_enable_flips_the_phase_each_call(rig, device):
    device.enable()
    for _ in range(4):
        device.toggle_enable()
    device.read_counters()
    phases = [flags & protocol.CommandFlags.ENABLE_TOGGLE for _, _, _, flags in list(rig.firmware.commands)[-5:]]
    assert phases in ([2, 0, 2, 0, 2], [0, 2, 0, 2, 0])


def test_garbage_and_truncated_frames_before_a_reply_are_rejected_and_counted(rig, device):
    rig.firmware.garbage_before_next_reply = b"\x13\x37garbage\x00\x00\xff\x01"
    assert device.read_counters().counts == COUNTS
    rig.firmware.truncated_frame_before_next_reply = True
    assert device.read_counters().counts == COUNTS
    assert device.decoder.error_count >= 2


def test_bad_crc_reply_is_rejected_then_the_stream_resyncs(rig, device):
    rig.firmware.corrupt_next_reply_crc = True
    with pytest.raises(DeviceError, match="no STATE reply.*CRC 1"):
        device.read_counters()
    assert device.decoder.crc_errors == 1
    assert device.read_counters().counts == COUNTS  # the port stays open and the next exchange works


def test_malformed_frames_from_the_host_are_counted_by_the_device(rig, device):
    device._port.write(b"\x00\x42\x42\x42\x00" + protocol.encode_frame(0x55, 0, b"") + b"\x00\x05\x00")
    device.read_counters()
    assert device.device_rx_errors == rig.firmware.rx_error_count == 3


def test_partial_reads_reassemble_a_reply_written_in_delayed_chunks(rig, device):
    rig.firmware.reply_chunks = 9
    rig.firmware.reply_chunk_delay_s = 0.003
    assert device.read_counters().counts == COUNTS
    assert device.decoder.error_count == 0


def test_late_reply_is_discarded_as_stale(rig, device):
    device.read_timeout_s = 0.05
    rig.firmware.delay_next_reply_s = 0.15
    with pytest.raises(DeviceError, match="no STATE reply"):
        device.read_counters()
    device.read_timeout_s = 0.5
    sample = device.read_counters()
    assert sample.counts == COUNTS
    assert device.stale_replies == 1


def test_disconnect_raises_device_error_then_open_reconnects(rig, device):
    device.enable()
    rig.firmware.disconnect()  # the master end closes: the slave reports a hang-up (EIO)
    with pytest.raises(DeviceError, match="disconnected"):
        device.read_counters()
    assert not device.is_open
    with pytest.raises(DeviceError, match="not open"):
        device.write_currents(0.1, 0.1)
    device.disable()  # safe on a broken link
    firmware = rig.plug_in()  # the board re-enumerates behind the same stable name
    firmware.counts = [9, 10, 11, 12]
    device.open()
    assert device.reconnects == 1
    assert device.read_counters().counts == (9, 10, 11, 12)
    device.enable()
    device.write_currents(0.2, 0.3)
    device.read_counters()
    assert firmware.applied_currents_ua == (200_000, 300_000)


def test_write_to_a_device_that_stopped_reading_times_out(rig, device):
    rig.firmware.reading = False
    start = time.monotonic()
    with pytest.raises(DeviceError, match="blocked longer than 0.005 s"):
        for _ in range(100_000):  # until the kernel's buffer is full
            device.write_currents(0.1, 0.1)
    assert time.monotonic() - start < 5.0
    assert not device.is_open


def test_device_watchdog_zeroes_currents_when_commands_stop(rig, device):
    device.enable()
    device.write_currents(1.0, 0.5)
    device.read_counters()
    assert rig.firmware.applied_currents_ua == (1_000_000, 500_000)
    time.sleep(0.1)  # no COMMAND for 100 ms > command_timeout_ms = 50
    assert rig.firmware.watchdog_tripped
    assert rig.firmware.applied_currents_ua == (0, 0) and not rig.firmware.outputs_enabled
    with pytest.raises(DeviceError, match="watchdog tripped"):
        device.read_counters()
    device.write_currents(1.0, 0.5)  # the trip is latched: commands alone do not restart the outputs
    device.read_counters()
    assert rig.firmware.applied_currents_ua == (0, 0)
    device.disable()
    device.enable()
    device.write_currents(1.0, 0.5)
    device.read_counters()
    assert rig.firmware.applied_currents_ua == (1_000_000, 500_000)


def test_outputs_stop_when_enable_toggles_stop(rig, device):
    device.enable()
    for _ in range(12):  # commands keep coming (no watchdog trip) but toggle_enable is never called
        device.write_currents(0.4, 0.4)
        time.sleep(0.01)
    assert not rig.firmware.outputs_enabled and rig.firmware.applied_currents_ua == (0, 0)
    with pytest.raises(DeviceError, match="no enable toggle"):
        device.read_counters()
    device.toggle_enable()
    device.read_counters()
    assert rig.firmware.applied_currents_ua == (400_000, 400_000)


def test_non_finite_current_sends_zero_and_raises(rig, device):
    device.enable()
    device.write_currents(0.5, 0.5)
    with pytest.raises(DeviceError, match="non-finite"):
        device.write_currents(float("nan"), 0.5)
    device.read_counters()
    assert rig.firmware.commands[-1][1:3] == (0, 0)


def test_open_failures_are_device_errors_with_a_reason(rig, tmp_path):
    with pytest.raises(DeviceError, match="cannot open '/nonexistent/ttyX'"):
        SerialDevice({"port": "/nonexistent/ttyX"}).open()
    rig.firmware.muted = True
    with pytest.raises(DeviceError, match="no HELLO_REPLY"):
        SerialDevice({"port": str(rig.link), "open_timeout_s": 0.2}).open()
    rig.firmware.muted = False
    rig.firmware.protocol_version = 7
    with pytest.raises(DeviceError, match="protocol version 7"):
        SerialDevice({"port": str(rig.link)}).open()
    rig.firmware.protocol_version = 1
    rig.firmware.counter_bits = 16
    with pytest.raises(DeviceError, match="counter_bits: 16"):
        SerialDevice({"port": str(rig.link)}).open()


def test_close_is_idempotent_and_leaves_outputs_off(rig, device):
    device.enable()
    device.write_currents(0.3, 0.3)
    device.close()
    device.close()
    assert wait_until(lambda: rig.firmware.commands and rig.firmware.commands[-1][1:] == (0, 0, 0))
    assert not rig.firmware.outputs_enabled
