"""A client of the Foxglove WebSocket protocol (``foxglove.websocket.v1``), written from its specification.

For tests that talk to a server as the Foxglove app does: it reads the server's info and advertisements, subscribes to
channels and decodes their message frames, calls services, and advertises a channel of its own to publish on.

Frames (the protocol's spec, foxglove/ws-protocol docs/spec.md): text frames are JSON objects with an ``op``; binary
frames start with an opcode byte. Server to client: 0x01 message data (uint32 subscription id, uint64 receive time
ns, payload), 0x03 service call response (uint32 service id, uint32 call id, uint32 encoding length, encoding,
payload), 0x04 fetch asset response (uint32 request id, uint8 status 0 found / 1 not, uint32 error length, error,
data). Client to server: 0x01 message data (uint32 channel id, payload), 0x02 service call request (as 0x03).
All integers little-endian. The protocol's subprotocol name is ``foxglove.websocket.v1``; foxglove-sdk's server
accepts only its new name for the same protocol, ``foxglove.sdk.v1``. The client offers both, as the Foxglove app
does.
"""
from __future__ import annotations

import base64
import dataclasses
import json
import socket
import struct
import threading
import time
from typing import Any, Optional, Sequence

from websockets.exceptions import ConnectionClosed
from websockets.sync.client import ClientConnection, connect
from websockets.typing import Subprotocol

#: the protocol's names, the SDK's first
SUBPROTOCOLS = ("foxglove.sdk.v1", "foxglove.websocket.v1")
SERVER_MESSAGE_DATA = 0x01
SERVER_SERVICE_CALL_RESPONSE = 0x03
SERVER_FETCH_ASSET_RESPONSE = 0x04
CLIENT_MESSAGE_DATA = 0x01
CLIENT_SERVICE_CALL_REQUEST = 0x02


@dataclasses.dataclass(frozen=True)
class MessageFrame:
    """One message of a subscribed channel.

    Its topic, the server's log time (ns), the payload as sent, and when this client read it (time.monotonic, s).
    """

    topic: str
    log_time_ns: int
    payload: bytes
    received_s: float


@dataclasses.dataclass(frozen=True)
class ServiceReply:
    """A service call's answer: its payload and encoding, or the server's failure message (then payload is None)."""

    payload: Optional[bytes]
    encoding: str = ""
    failure: str = ""


class FoxgloveClient:
    """A connection to url (``ws://host:port``).

    Text messages other than the awaited ones are kept in ``info``, ``channels``, ``services`` and ``statuses`` as they
    come.
    """

    def __init__(self, url: str, open_timeout_s: float = 10.0) -> None:
        self.port = int(url.rsplit(":", 1)[1].split("/")[0])
        self.connection: ClientConnection = connect(url, subprotocols=[Subprotocol(name) for name in SUBPROTOCOLS],
                                                    open_timeout=open_timeout_s,
                                                    max_size=None)
        self.info: dict[str, Any] = {}
        self.channels: dict[int, dict[str, Any]] = {}      # channel id -> its advertisement
        self.services: dict[str, dict[str, Any]] = {}      # service name -> its advertisement
        self.statuses: list[dict[str, Any]] = []
        self._subscriptions: dict[int, str] = {}           # subscription id -> topic
        self._replies: dict[int, ServiceReply] = {}        # call id -> its answer
        self._assets: dict[int, tuple[Optional[bytes], str]] = {}   # request id -> (data or None, error)
        self._messages: list[MessageFrame] = []
        self._next_id = 1
        self.closed = False   # the server closed the connection (it stopped)

    def close(self) -> None:
        """Close the connection."""
        self.connection.close()

    def __enter__(self) -> "FoxgloveClient":
        """The client itself, closed when the block ends."""
        return self

    def __exit__(self, *_: object) -> None:
        """Close the connection."""
        self.close()

    def _new_id(self) -> int:
        self._next_id += 1
        return self._next_id

    def _receive(self, timeout_s: float) -> bool:  # noqa: C901 - one branch per message kind of the protocol
        """Read one frame within timeout_s and file it; False if none came (or the connection is closed)."""
        if self.closed:
            return False
        try:
            frame = self.connection.recv(timeout=timeout_s)
        except TimeoutError:
            return False
        except ConnectionClosed:
            self.closed = True
            return False
        if isinstance(frame, str):
            message = json.loads(frame)
            op = message.get("op")
            if op == "serverInfo":
                self.info = message
            elif op == "advertise":
                self.channels.update({channel["id"]: channel for channel in message["channels"]})
            elif op == "unadvertise":
                for channel_id in message["channelIds"]:
                    self.channels.pop(channel_id, None)
            elif op == "advertiseServices":
                self.services.update({service["name"]: service for service in message["services"]})
            elif op == "serviceCallFailure":
                self._replies[message["callId"]] = ServiceReply(None, failure=message["message"])
            elif op == "status":
                self.statuses.append(message)
            return True
        opcode = frame[0]
        if opcode == SERVER_MESSAGE_DATA:
            subscription, log_time_ns = struct.unpack_from("<IQ", frame, 1)
            if subscription in self._subscriptions:
                self._messages.append(MessageFrame(self._subscriptions[subscription], log_time_ns, bytes(frame[13:]),
                                                   time.monotonic()))
        elif opcode == SERVER_FETCH_ASSET_RESPONSE:
            request_id, status, error_length = struct.unpack_from("<IBI", frame, 1)
            error = bytes(frame[10:10 + error_length]).decode()
            self._assets[request_id] = (bytes(frame[10 + error_length:]) if status == 0 else None, error)
        elif opcode == SERVER_SERVICE_CALL_RESPONSE:
            _, call_id, encoding_length = struct.unpack_from("<III", frame, 1)
            encoding = bytes(frame[13:13 + encoding_length]).decode()
            self._replies[call_id] = ServiceReply(bytes(frame[13 + encoding_length:]), encoding)
        return True

    def wait_for(self, condition: Any, timeout_s: float) -> bool:
        """Read frames until condition() holds, timeout_s passes or the server closes; whether it holds."""
        deadline = time.monotonic() + timeout_s
        while not condition():
            remaining_s = deadline - time.monotonic()
            if remaining_s <= 0.0 or self.closed:
                return False
            self._receive(min(remaining_s, 0.1))
        return True

    def channel(self, topic: str, timeout_s: float = 10.0) -> dict[str, Any]:
        """The advertisement of topic's channel, waited for; KeyError if none came within timeout_s."""
        def found() -> Optional[dict[str, Any]]:
            return next((c for c in self.channels.values() if c["topic"] == topic), None)
        if not self.wait_for(lambda: found() is not None, timeout_s):
            topics = sorted(c["topic"] for c in self.channels.values())
            raise KeyError(f"no channel {topic!r} advertised within {timeout_s} s: {topics}")
        channel = found()
        assert channel is not None
        return channel

    def subscribe(self, topic: str, timeout_s: float = 10.0) -> int:
        """Subscribe to topic once its channel is advertised (within timeout_s, s); the subscription id."""
        channel = self.channel(topic, timeout_s)
        subscription = self._new_id()
        self._subscriptions[subscription] = topic
        self.connection.send(json.dumps({"op": "subscribe",
                                         "subscriptions": [{"id": subscription, "channelId": channel["id"]}]}))
        return subscription

    def messages(self, topic: str) -> list[MessageFrame]:
        """The frames received so far on topic (read more with wait_for or receive_for)."""
        return [message for message in self._messages if message.topic == topic]

    def receive_for(self, duration_s: float) -> None:
        """Read whatever comes for duration_s."""
        self.wait_for(lambda: False, duration_s)

    def call_service(self, name: str, payload: bytes, encoding: str = "json", timeout_s: float = 30.0) -> ServiceReply:
        """Call the service name with payload; its reply (TimeoutError if none within timeout_s)."""
        if not self.wait_for(lambda: name in self.services, timeout_s):
            raise KeyError(f"no service {name!r} advertised: {sorted(self.services)}")
        call_id = self._new_id()
        encoded = encoding.encode()
        self.connection.send(struct.pack("<BIII", CLIENT_SERVICE_CALL_REQUEST, self.services[name]["id"], call_id,
                                         len(encoded)) + encoded + payload)
        if not self.wait_for(lambda: call_id in self._replies, timeout_s):
            raise TimeoutError(f"no reply from {name!r} within {timeout_s} s")
        return self._replies.pop(call_id)

    def fetch_asset(self, uri: str, timeout_s: float = 10.0) -> tuple[Optional[bytes], str]:
        """The asset at uri as the server gives it (the 3D panel asks for a URDF's meshes so).

        (its bytes, "") or (None, the server's error).
        """
        request_id = self._new_id()
        self.connection.send(json.dumps({"op": "fetchAsset", "uri": uri, "requestId": request_id}))
        if not self.wait_for(lambda: request_id in self._assets, timeout_s):
            raise TimeoutError(f"no answer for the asset {uri!r} within {timeout_s} s")
        return self._assets.pop(request_id)

    def advertise(self, topic: str, encoding: str = "json", schema_name: str = "") -> int:
        """Advertise a channel of this client's on topic; its id, to publish with."""
        channel_id = self._new_id()
        self.connection.send(json.dumps({"op": "advertise", "channels": [
            {"id": channel_id, "topic": topic, "encoding": encoding, "schemaName": schema_name}]}))
        return channel_id

    def publish(self, channel_id: int, payload: bytes) -> None:
        """Send payload on channel_id, a channel this client advertised."""
        self.connection.send(struct.pack("<BI", CLIENT_MESSAGE_DATA, channel_id) + payload)


def decode_protobuf(schema_name: str, file_descriptor_set: bytes, payload: bytes) -> Any:
    """A protobuf message (a foxglove schema's, e.g. foxglove.FrameTransforms) decoded by the schema it came with.

    Its name and a serialized FileDescriptorSet (what a channel advertises, base64-decoded: ``channel_schema``).
    """
    from google.protobuf import descriptor_pb2, descriptor_pool, message_factory
    files = descriptor_pb2.FileDescriptorSet.FromString(file_descriptor_set)
    pool = descriptor_pool.DescriptorPool()
    for file in files.file:
        pool.Add(file)
    return message_factory.GetMessageClass(pool.FindMessageTypeByName(schema_name)).FromString(payload)


def channel_schema(channel: dict[str, Any]) -> bytes:
    """An advertised channel's schema as bytes.

    Binary schemas (protobuf's) come base64-encoded, text ones as they are.
    """
    if channel.get("schemaEncoding") == "protobuf":
        return base64.b64decode(channel["schema"])
    return str(channel["schema"]).encode()


def free_port() -> int:
    """A TCP port free on loopback now, for a server a test or bench starts."""
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def connect_when_listening(port: int, stop: threading.Event) -> Optional[FoxgloveClient]:
    """A client of the server on 127.0.0.1:port, or None if stop is set first.

    It connects as soon as the server listens (a node that is still starting).
    """
    while not stop.is_set():
        try:
            return FoxgloveClient(f"ws://127.0.0.1:{port}")
        except OSError:
            stop.wait(0.05)
    return None


def transform_key(sec: int, nanosec: int, parent: str, child: str, translation: Any, rotation: Any) -> tuple:
    """A transform as a comparable tuple, its numbers to 1e-12.

    Either tf2's or Foxglove's: translation x, y, z and rotation x, y, z, w.
    """
    return (int(sec), int(nanosec), parent, child, *(round(v, 12) for v in (
        translation.x, translation.y, translation.z, rotation.x, rotation.y, rotation.z, rotation.w)))


def tf_message_keys(message: Any) -> set[tuple]:
    """The transform_keys of a tf2_msgs/TFMessage."""
    return {transform_key(t.header.stamp.sec, t.header.stamp.nanosec, t.header.frame_id, t.child_frame_id,
                          t.transform.translation, t.transform.rotation) for t in message.transforms}


def frame_transforms_keys(client: FoxgloveClient, topic: str = "/tf") -> list[tuple]:
    """The transform_keys of every foxglove.FrameTransforms message client received on topic.

    Each message is decoded by the channel's advertised schema.
    """
    channel = client.channel(topic)
    keys = []
    for message in client.messages(topic):
        for t in decode_protobuf(channel["schemaName"], channel_schema(channel), message.payload).transforms:
            keys.append(transform_key(t.timestamp.seconds, t.timestamp.nanos, t.parent_frame_id, t.child_frame_id,
                                      t.translation, t.rotation))
    return keys


class ClientThread(threading.Thread):
    """A client on a thread of its own, as a Foxglove app beside a run.

    It connects as soon as the server on 127.0.0.1:port listens, subscribes to topics (None: every channel, once at
    least min_channels are advertised), and then reads until stopped, or never reads (read False: a stalled app).
    ``subscribed`` is set once it has subscribed; ``client`` holds what it received.
    """

    def __init__(self, port: int, topics: Optional[Sequence[str]] = None, read: bool = True,
                 min_channels: int = 1) -> None:
        super().__init__(daemon=True)
        self.port, self.topics, self.read, self.min_channels = port, topics, read, min_channels
        self.stop, self.subscribed = threading.Event(), threading.Event()
        self.client: Optional[FoxgloveClient] = None

    def run(self) -> None:
        """Connect and subscribe, then read until stop is set or the connection closes (never with read False)."""
        self.client = client = connect_when_listening(self.port, self.stop)
        if client is None:
            return
        with client:
            if self.topics is None:
                client.wait_for(lambda: len(client.channels) >= self.min_channels, 30.0)
                self.topics = sorted(channel["topic"] for channel in client.channels.values())
            for topic in self.topics:
                client.subscribe(topic, timeout_s=30.0)
            self.subscribed.set()
            while self.read and not self.stop.is_set() and not client.closed:
                client.receive_for(0.05)
            self.stop.wait()
