"""Bags of a run, written and read with rosbags (rosbag2 MCAP, readable by `ros2 bag info` on a full install).

Messages are stored as the CDR bytes rclpy received (no re-encoding); the bag's connections carry the full
message definitions, ours included (from swim_interfaces' installed .msg files), so any rosbag2 reader can
decode them. A bag is written in chunks (MCAP); flush() ends the chunk under way and puts it on disk, so a
recorder killed before close() leaves a bag whose written chunks read_messages still reads (without the summary
and metadata.yaml that close() writes).

Any rosbag2 bag reads back (bag_info, read_messages): a folder with its metadata.yaml and MCAP or sqlite3 (.db3)
files, or one .mcap or .db3 file. Topic names are as recorded: rosbag2, swim-record and swim-demo's client
(RUN_TOPICS) give full names (/joint_states); other recorders may give relative ones (joint_states), which
analysis.find_topic finds too. Messages are decoded by the definition of their type that the bag carries (the one
they were recorded with), and by the installed one only where the bag has none:
a bag recorded with an older version of our messages (swim_interfaces v2's PlannedTrajectory, before the flow
model's fields) reads as it was written. What cannot be read (no bag at the path, a corrupt file, a message whose
type neither the bag defines nor this environment knows) is a BagError that says which and why; undecodable_topics
names, before reading, the topics whose messages cannot be decoded, with why.

An MCAP bag that rosbags cannot open is read with the mcap library (Foxglove's reader) instead: rosbag2 (Humble)
writes a schema of encoding 'unknown', with no definition, for a type whose definition it could not find (an
action's feedback message, say), and rosbags has no format for that encoding. Such a bag lists every topic from its
MCAP summary; the messages of a type without a definition decode when this environment knows the type, and are
named undecodable otherwise. The mcap library reads one file: a bag folder of several MCAP files (a split bag)
rosbags cannot open is a BagError that says to give one of them.
"""
from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any, Callable, Iterator, Sequence, Union

from rosbags.interfaces import MessageDefinition, MessageDefinitionFormat, Qos
from rosbags.rosbag2 import Reader, ReaderError, StoragePlugin, Writer
from rosbags.typesys import Stores, TypesysError, get_types_from_idl, get_types_from_msg, get_typestore
from rosbags.typesys.store import Typestore

from swim_ros.typestore import swim_typestore

#: the run's topics and their types (the demo records all of them), by their fully qualified names: the nodes of a
#: run are in the root namespace, and rosbag2, swim-record and Foxglove's layouts (docs/foxglove_layout.json) name
#: topics in full
RUN_TOPICS = {
    "/joint_states": "sensor_msgs/msg/JointState",
    "/joint_commands": "sensor_msgs/msg/JointState",
    "/tracking_state": "swim_interfaces/msg/TrackingState",
    "/plan": "swim_interfaces/msg/PlannedTrajectory",
    "/wake_statistics": "swim_interfaces/msg/WakeStatistics",   # only with the simulator's flow: wake
    "/wake_vortices": "swim_interfaces/msg/WakeVortices",       # only with the simulator's flow: wake
    "/diagnostics": "diagnostic_msgs/msg/DiagnosticArray",       # bridge_node's loop, watchdog and faults
    "/robot_description": "std_msgs/msg/String",                 # swim_viz's rig_state_publisher: the URDF
    "/tf": "tf2_msgs/msg/TFMessage",                             # ... the rig's moving frames
    "/tf_static": "tf2_msgs/msg/TFMessage",                      # ... and its fixed ones
    "/markers": "visualization_msgs/msg/MarkerArray",            # swim_viz's marker_node: planned, travelled path
}
#: the latched topics (transient local, depth 1): a recorder that subscribes late still gets their last message
LATCHED_TOPICS = ("/plan", "/robot_description", "/tf_static")


class BagError(RuntimeError):
    """A bag that cannot be read or written as asked (an unknown message type, a folder without a bag)."""


class BagWriter:
    """An MCAP rosbag2 bag of raw CDR messages, one connection per topic."""

    def __init__(self, path: Path, topics: dict[str, str] = RUN_TOPICS) -> None:
        self.store = swim_typestore()
        self._writer: Writer | None = Writer(path, version=9, storage_plugin=StoragePlugin.MCAP)
        self._writer.open()
        self._connections: dict[str, Any] = {}
        self.counts: dict[str, int] = {}
        for topic, msgtype in topics.items():
            self.add_topic(topic, msgtype)

    def add_topic(self, topic: str, msgtype: str, offered_qos: Sequence[Qos] = ()) -> None:
        """A connection for a topic of a message type.

        A connection for topic, of type msgtype (e.g. 'sensor_msgs/msg/JointState'), with the QoS profiles its
        publishers offer (for metadata.yaml and a player). BagError for a type the type store does not know.
        """
        assert self._writer is not None, "BagWriter.add_topic after close()"
        if msgtype not in self.store.fielddefs:
            raise BagError(f"unknown message type {msgtype} (topic {topic}): not a ROS 2 Jazzy type nor ours")
        self._connections[topic] = self._writer.add_connection(topic, msgtype, typestore=self.store,
                                                               offered_qos_profiles=offered_qos)
        self.counts[topic] = 0

    def write(self, topic: str, timestamp_ns: int, cdr: bytes) -> None:
        """Write one message's CDR bytes on topic, stamped timestamp_ns (ns)."""
        assert self._writer is not None, "BagWriter.write after close()"
        self._writer.write(self._connections[topic], timestamp_ns, cdr)
        self.counts[topic] += 1

    def flush(self) -> None:
        """End the chunk under way and put everything written on disk.

        End the chunk under way, if any, and put everything written on disk: a recorder killed after this
        leaves a bag that reads up to here.
        """
        assert self._writer is not None, "BagWriter.flush after close()"
        storage: Any = self._writer.storage   # rosbags' MCAP storage: chunks of up to 1 MiB, on its own file
        if storage.chunk.bio.tell():
            storage.close_chunk()
        storage.bio.flush()

    def close(self) -> None:
        """Finish the bag (its summary and metadata.yaml); safe to call twice."""
        if self._writer is not None:
            self._writer.close()
            self._writer = None


@dataclasses.dataclass(frozen=True)
class TopicInfo:
    """A topic of a bag with its type and message count.

    A topic of a bag: its name as recorded, its type (e.g. 'sensor_msgs/msg/JointState') and how many messages
    the bag holds on it.
    """

    name: str
    msgtype: str
    message_count: int


@dataclasses.dataclass(frozen=True)
class BagInfo:
    """What a bag holds, from its metadata (a bag cut before close(): from a linear read of its complete chunks)."""

    path: Path
    storage: str                 # 'mcap' or 'sqlite3'
    complete: bool               # False: cut before close(), no metadata.yaml; read up to its last complete chunk
    topics: tuple[TopicInfo, ...]

    @property
    def message_count(self) -> int:
        """The number of messages over all topics."""
        return sum(topic.message_count for topic in self.topics)


def _is_cut_bag(path: Path) -> bool:
    return path.is_dir() and not (path / "metadata.yaml").is_file()


#: the bytes an MCAP file starts and, once closed, ends with
MCAP_MAGIC = b"\x89MCAP0\r\n"


def _open_reader(path: Path) -> Reader | None:
    """An open rosbags Reader of the bag at path, or None for an MCAP bag rosbags cannot open.

    An open rosbags Reader of the bag folder or storage file at path; None for an MCAP bag that rosbags cannot
    open, which the mcap library reads instead (_mcap_file gives its file): one with a schema encoding rosbags has no
    format for (rosbag2's 'unknown'), or one MCAP file cut short (no summary, no closing magic: its recorder was
    killed). BagError if it is not a readable bag.
    """
    if not path.exists():
        raise BagError(f"{path}: no such file or folder")
    try:
        reader = Reader(path)
        reader.open()
    except (ReaderError, OSError) as err:
        if path.is_file() and path.suffix == ".mcap" and _cut_short(path):
            return None
        raise BagError(f"{path}: not a readable rosbag2 bag: {err}") from err
    except KeyError as err:   # rosbags' MCAP storage: a schema encoding it has no format for
        _mcap_file(path, f"rosbags cannot open it (an MCAP schema of encoding {err})")
        return None
    return reader


def _cut_short(file: Path) -> bool:
    """Whether the MCAP file at file starts as one but does not end as a closed one does."""
    with open(file, "rb") as stream:
        start = stream.read(len(MCAP_MAGIC))
        stream.seek(max(file.stat().st_size - len(MCAP_MAGIC), 0))
        return start == MCAP_MAGIC and stream.read() != MCAP_MAGIC


def _mcap_summary(file: Path) -> Any:
    """The summary of the MCAP file, or None for a file without one.

    The summary of the MCAP file (the mcap library's Summary); None for a file without one (cut short, or
    closed without it). BagError if it does not read.
    """
    from mcap.exceptions import McapError
    from mcap.reader import make_reader
    if _cut_short(file):
        return None
    with open(file, "rb") as stream:
        try:
            return make_reader(stream).get_summary()
        except (McapError, ValueError) as err:   # ValueError: a summary that does not parse
            raise BagError(f"{file}: not a readable MCAP file: {type(err).__name__}: {err}") from err


def _mcap_file(path: Path, why: str) -> Path:
    """The one MCAP file of the bag at path.

    The file is path itself, or the one its folder holds, for the mcap library to read where rosbags cannot (why);
    BagError if there is not exactly one.
    """
    files = [path] if path.is_file() else sorted(path.glob("*.mcap"))
    if len(files) != 1 or files[0].suffix != ".mcap":
        raise BagError(f"{path}: {why}, and the mcap library reads one MCAP file: "
                       + (f"give one of its {len(files)} MCAP files" if len(files) > 1 else "it holds none"))
    return files[0]


def _bag_topics(path: Path) -> tuple[BagInfo, dict[str, tuple[str, MessageDefinition]]]:
    """bag_info of the bag at path, and each topic's type and the definition of it the bag carries."""
    path = Path(path)
    if _is_cut_bag(path):
        return _linear_topics(path, _cut_bag_records(path))
    reader = _open_reader(path)
    if reader is None:
        return _mcap_topics(path)
    try:
        storage = "sqlite3" if path.suffix == ".db3" or any(path.glob("*.db3")) else "mcap"
        return (BagInfo(path, storage, True, tuple(TopicInfo(c.topic, c.msgtype, c.msgcount)
                                                   for c in reader.connections)),
                {c.topic: (c.msgtype, c.msgdef) for c in reader.connections})
    finally:
        reader.close()


def _linear_topics(path: Path, records: Iterator[tuple[str, str, int, bytes | None, MessageDefinition]]
                   ) -> tuple[BagInfo, dict[str, tuple[str, MessageDefinition]]]:
    """_bag_topics of an MCAP bag without summary (its recorder was cut off), from a linear read of its records."""
    counts: dict[tuple[str, str], int] = {}
    definitions: dict[str, tuple[str, MessageDefinition]] = {}
    for topic, msgtype, _, raw, definition in records:
        counts[topic, msgtype] = counts.get((topic, msgtype), 0) + (raw is not None)
        definitions[topic] = (msgtype, definition)
    topics = tuple(TopicInfo(topic, msgtype, count) for (topic, msgtype), count in counts.items())
    return BagInfo(path, "mcap", False, topics), definitions


def _mcap_topics(path: Path) -> tuple[BagInfo, dict[str, tuple[str, MessageDefinition]]]:
    """The topics of an MCAP bag rosbags cannot open, read with the mcap library.

    _bag_topics of an MCAP bag rosbags cannot open, with the mcap library: every channel of its summary, its
    schema's name as type; without summary or statistics, from a linear read.
    """
    file = _mcap_file(path, "rosbags cannot open it")
    summary = _mcap_summary(file)
    if summary is None or summary.statistics is None:
        return _linear_topics(path, _mcap_records(file))
    counts = summary.statistics.channel_message_counts
    channels = {c.id: (c.topic, *_schema_definition(summary.schemas.get(c.schema_id)))
                for c in summary.channels.values()}
    topics = tuple(TopicInfo(topic, msgtype, counts.get(channel_id, 0))
                   for channel_id, (topic, msgtype, _) in channels.items())
    return (BagInfo(path, "mcap", True, topics),
            {topic: (msgtype, definition) for topic, msgtype, definition in channels.values()})


def _schema_definition(schema: Any) -> tuple[str, MessageDefinition]:
    """The type name and definition an MCAP schema carries.

    The type name and the definition an MCAP schema (the mcap library's record; None: a channel without schema)
    carries; a definition of an encoding rosbags has no format for (rosbag2's 'unknown') is no definition.
    """
    if schema is None:
        return "", MessageDefinition(MessageDefinitionFormat.NONE, "")
    return schema.name, MessageDefinition(SCHEMA_FORMATS.get(schema.encoding, MessageDefinitionFormat.NONE),
                                          schema.data.decode(errors="replace"))


def bag_info(path: Path) -> BagInfo:
    """The topics of the bag at path with their types and message counts.

    The topics of the bag at path (a folder, or one .mcap or .db3 file) with their types and message counts.
    BagError if there is no readable bag there.
    """
    return _bag_topics(path)[0]


def undecodable_topics(path: Path) -> dict[str, str]:
    """The topics of the bag at path whose messages cannot be decoded, each with why.

    Each is of a type that neither the bag defines (in a definition that parses) nor this environment knows. BagError if
    there is no readable bag there.
    """
    return bag_contents(path)[1]


def bag_contents(path: Path) -> tuple[BagInfo, dict[str, str]]:
    """The topics and the undecodable topics of the bag at path, from one read.

    bag_info and undecodable_topics of the bag at path, from one read of its index. BagError if there is no
    readable bag there.
    """
    info, definitions = _bag_topics(path)
    decoder = BagDecoder(Path(path))
    return info, {topic: why for topic, (msgtype, definition) in definitions.items()
                  if (why := decoder.why_undecodable(msgtype, definition))}


#: MCAP schema encodings (rosbag2's) as rosbags names the formats of message definitions
SCHEMA_FORMATS = {"ros2msg": MessageDefinitionFormat.MSG, "ros2idl": MessageDefinitionFormat.IDL,
                  "omgidl": MessageDefinitionFormat.IDL}
#: the line rosbag2 puts between the IDL definitions of a type and the types it uses
IDL_SEPARATOR = "=" * 80 + "\n"


def definition_types(msgtype: str, definition: MessageDefinition) -> dict[str, Any]:
    """The types of a bag's own definition of msgtype.

    The types are msgtype and every type it uses, as the bag's recorder knew them, parsed by rosbags; empty when the bag
    has no definition or one rosbags cannot parse.
    """
    try:
        if definition.format == MessageDefinitionFormat.MSG:
            return dict(get_types_from_msg(definition.data, msgtype))
        if definition.format == MessageDefinitionFormat.IDL:
            types: dict[str, Any] = {}
            if definition.data.startswith(f"{IDL_SEPARATOR}IDL: "):
                for part in definition.data.split(IDL_SEPARATOR)[1:]:
                    types.update(get_types_from_idl(part.split("\n", 1)[1]))
            else:
                types.update(get_types_from_idl(definition.data))
            return types
    except (TypesysError, IndexError):   # a definition that does not parse: the installed type is used instead
        pass
    return {}


def _no_definition(msgtype: str, definition: MessageDefinition) -> str:
    """How the bag fails to define msgtype (definition_types found no type of that name in its definition)."""
    if not msgtype:
        return "its channel has no schema: no type to decode its messages by"
    if definition.format == MessageDefinitionFormat.NONE or not definition.data.strip():
        return f"the bag carries no definition of {msgtype}"
    return f"the bag's definition of {msgtype} ({definition.format.name}) does not parse"


class BagDecoder:
    """A decoder of the messages of one bag.

    Decodes the messages of one bag: each by its own type's definition in the bag (the one it was recorded with),
    or by the installed one (swim_typestore) where the bag has none.
    """

    def __init__(self, path: Path) -> None:
        self.path = path
        self._installed: Typestore | None = None
        self._stores: dict[tuple[str, MessageDefinition], Typestore] = {}

    def store(self, topic: str, msgtype: str, definition: MessageDefinition) -> Typestore:
        """The type store msgtype is decoded with; BagError if neither the bag nor this environment defines it."""
        key = (msgtype, definition)
        if key not in self._stores:
            types = definition_types(msgtype, definition)
            if msgtype in types:
                store = get_typestore(Stores.EMPTY)
                store.register(types)
            else:
                if self._installed is None:
                    self._installed = swim_typestore()
                store = self._installed
                if msgtype not in store.fielddefs:
                    raise BagError(f"{self.path}: {topic} is of type {msgtype}, which neither the bag defines nor "
                                   f"this environment knows (ROS 2 Jazzy's types and swim_interfaces'): "
                                   f"{_no_definition(msgtype, definition)}")
            self._stores[key] = store
        return self._stores[key]

    def why_undecodable(self, msgtype: str, definition: MessageDefinition) -> str:
        """Why messages of msgtype, of which the bag carries definition, cannot be decoded; '' when they can."""
        try:
            self.store("", msgtype, definition)
        except BagError:
            if not msgtype:
                return _no_definition(msgtype, definition)
            return (f"{_no_definition(msgtype, definition)}, and this environment does not know the type (ROS 2 "
                    f"Jazzy's types and swim_interfaces' are known)")
        return ""

    def decode(self, topic: str, timestamp: int, msgtype: str, definition: MessageDefinition, raw: bytes) -> Any:
        """The message on topic at timestamp (ns), decoded as msgtype; BagError if it does not decode."""
        store = self.store(topic, msgtype, definition)
        try:
            return store.deserialize_cdr(raw, msgtype)
        except Exception as err:   # rosbags' generated deserializers raise whatever error the bad bytes trip
            raise BagError(f"{self.path}: the message on {topic} at {timestamp} ns does not decode as {msgtype} "
                           f"({type(err).__name__}: {err})") from err


#: a message as the bag stores it: (topic, log time ns, type name, the definition of its type the bag carries, CDR)
RawMessage = tuple[str, int, str, MessageDefinition, bytes]
#: called with (topic, type name, definition) for each topic asked that the bag lists, before any message is read
TopicCheck = Callable[[str, str, MessageDefinition], object]


def read_messages(path: Path, topics: tuple[str, ...]) -> Iterator[tuple[str, int, Any]]:
    """The decoded messages of the topics asked, in log-time order.

    (topic, log time ns, decoded message: the typestore's class of its type) for the topics asked (names exactly
    as recorded; a topic not in the bag gives nothing), in log-time order; of a bag cut before close() (no
    metadata.yaml), the messages of its complete chunks in the order written. BagError if the bag cannot be read
    or a message asked for cannot be decoded (its type neither defined in the bag nor known here, its bytes not of
    its type). Each message is decoded by its type's definition in the bag (BagDecoder).
    """
    decoder = BagDecoder(Path(path))
    for topic, timestamp, msgtype, definition, raw in _raw_messages(Path(path), topics, decoder.store):
        yield topic, timestamp, decoder.decode(topic, timestamp, msgtype, definition, raw)


#: a topic's messages as read_topics gives them: (log time ns, decoded message) each, or why they cannot be read
TopicMessages = Union[list[tuple[int, Any]], BagError]


def read_topics(path: Path, topics: tuple[str, ...]) -> dict[str, TopicMessages]:
    """Each topic asked with its decoded messages, or the error that says why it has none.

    Each topic asked (names exactly as recorded) with its messages, (log time ns, decoded message) in
    read_messages' order, from one read of the bag; a topic not in the bag has none. A topic whose messages cannot
    be decoded gets the BagError that says why, and the others their messages; a bag whose messages cannot be read
    gives that BagError to every topic not already failed.
    """
    path = Path(path)
    decoder = BagDecoder(path)
    read: dict[str, TopicMessages] = {topic: [] for topic in topics}

    def check(topic: str, msgtype: str, definition: MessageDefinition) -> None:
        try:
            decoder.store(topic, msgtype, definition)
        except BagError as err:
            read[topic] = err
    try:
        for topic, timestamp, msgtype, definition, raw in _raw_messages(path, topics, check):
            messages = read[topic]
            if isinstance(messages, list):
                try:
                    messages.append((timestamp, decoder.decode(topic, timestamp, msgtype, definition, raw)))
                except BagError as err:
                    read[topic] = err
    except BagError as err:
        return {topic: messages if isinstance(messages, BagError) else err for topic, messages in read.items()}
    return read


def _raw_messages(path: Path, topics: tuple[str, ...], check: TopicCheck) -> Iterator[RawMessage]:
    """The stored messages of the topics asked, in log-time order.

    Of a cut bag they come in the order written. The check function is called for each topic asked that the bag's index
    lists, before any message is read (a cut bag has no index). BagError if the bag cannot be read.
    """
    if _is_cut_bag(path):
        for topic, msgtype, timestamp, raw, definition in _cut_bag_records(path):
            if raw is not None and topic in topics:
                yield topic, timestamp, msgtype, definition, raw
        return
    reader = _open_reader(path)
    if reader is None:
        yield from _mcap_messages(path, topics, check)
        return
    try:
        connections = [c for c in reader.connections if c.topic in topics]
        if not connections:   # rosbags reads every message when given no connection
            return
        for connection in connections:
            check(connection.topic, connection.msgtype, connection.msgdef)
        try:
            for connection, timestamp, raw in reader.messages(connections=connections):
                yield connection.topic, timestamp, connection.msgtype, connection.msgdef, raw
        except ReaderError as err:
            raise BagError(f"{path}: cannot read its messages: {err}") from err
    finally:
        reader.close()


def _mcap_messages(path: Path, topics: tuple[str, ...], check: TopicCheck) -> Iterator[RawMessage]:
    """The stored messages of an MCAP bag rosbags cannot open, read with the mcap library.

    _raw_messages of an MCAP bag rosbags cannot open, with the mcap library: by its index in log-time order;
    without summary, linearly in the order written.
    """
    from mcap.exceptions import McapError
    from mcap.reader import make_reader
    file = _mcap_file(path, "rosbags cannot open it")
    summary = _mcap_summary(file)
    if summary is None or not summary.chunk_indexes:
        for topic, msgtype, timestamp, raw, definition in _mcap_records(file):
            if raw is not None and topic in topics:
                yield topic, timestamp, msgtype, definition, raw
        return
    for channel in summary.channels.values():   # every topic asked is checked before any message is read
        if channel.topic in topics:
            check(channel.topic, *_schema_definition(summary.schemas.get(channel.schema_id)))
    with open(file, "rb") as stream:
        try:
            for schema, channel, message in make_reader(stream).iter_messages(topics=list(topics),
                                                                             log_time_order=True):
                yield (channel.topic, message.log_time, *_schema_definition(schema), message.data)
        except (McapError, ValueError) as err:
            raise BagError(f"{file}: cannot read its messages: {type(err).__name__}: {err}") from err


def read_cut_bag(path: Path) -> Iterator[tuple[str, str, int, bytes | None]]:
    """The messages in the complete chunks of a bag folder's MCAP file without summary.

    (topic, type name, log time ns, CDR bytes) of every message in the complete chunks of a bag folder's MCAP
    file that has no summary (its recorder was killed), in the order written, read linearly with the mcap library
    (Foxglove's reader) up to the first incomplete record; and (topic, type name, 0, None) for each channel as it
    is declared (a topic recorded without messages). BagError if the folder has no single MCAP file.
    """
    for topic, msgtype, timestamp, raw, _ in _cut_bag_records(path):
        yield topic, msgtype, timestamp, raw


def _cut_bag_records(path: Path) -> Iterator[tuple[str, str, int, bytes | None, MessageDefinition]]:
    """read_cut_bag's records, each with the definition of its type the bag carries (its channel's schema)."""
    files = sorted(Path(path).glob("*.mcap"))
    databases = sorted(p.name for p in Path(path).glob("*.db3"))
    if databases and not files:
        raise BagError(f"{path}: a sqlite3 bag without its metadata.yaml: give its file ({', '.join(databases)}) "
                       f"instead of the folder")
    if len(files) != 1:
        raise BagError(f"{path}: not a rosbag2 bag: no metadata.yaml, and "
                       + (f"{len(files)} MCAP files (give one of them)" if files else "no .mcap or .db3 file"))
    yield from _mcap_records(files[0])


def _mcap_records(file: Path) -> Iterator[tuple[str, str, int, bytes | None, MessageDefinition]]:
    """The messages of an MCAP file read linearly, up to the first incomplete record.

    (topic, type name, log time ns, CDR bytes, the definition of its type the file carries) of every message of
    the MCAP file, read linearly in the order written up to the first incomplete record (a file cut short); and
    (topic, type name, 0, None, definition) for each channel as it is declared. BagError if it is not MCAP.
    """
    from mcap.exceptions import EndOfFile, McapError
    from mcap.records import Channel, Message, Schema
    from mcap.stream_reader import StreamReader
    schemas: dict[int, tuple[str, MessageDefinition]] = {}
    channels: dict[int, tuple[str, str, MessageDefinition]] = {}
    with open(file, "rb") as stream:
        try:
            for record in StreamReader(stream, skip_magic=False, validate_crcs=False).records:
                if isinstance(record, Schema):
                    schemas[record.id] = _schema_definition(record)
                elif isinstance(record, Channel):
                    msgtype, definition = schemas[record.schema_id] if record.schema_id else _schema_definition(None)
                    channels[record.id] = (record.topic, msgtype, definition)
                    yield record.topic, msgtype, 0, None, definition
                elif isinstance(record, Message):
                    topic, msgtype, definition = channels[record.channel_id]
                    yield topic, msgtype, record.log_time, record.data, definition
        except EndOfFile:
            return
        except (McapError, KeyError) as err:   # not MCAP, or a record naming a schema or channel never declared
            raise BagError(f"{file}: not a readable MCAP file: {type(err).__name__}: {err}") from err
