"""Cuts the bag that rosbag2 (ROS 2 Humble) recorded, found in the sdist of mcap-bag-parser 0.3.1 (MIT), down to
bagfile_0_cut.mcap beside this script (SOURCE.md says where it comes from and what was kept).

The original (bagfile_0.mcap, 7.9 MB) is: the magic and rosbag2's Header and Metadata records; ten uncompressed
chunks of about 787 kB, each followed by its MessageIndex records; DataEnd; the summary (every Schema and Channel
record again, Statistics, ChunkIndex, MetadataIndex, SummaryOffset) and the Footer. The cut keeps, byte for byte:
- the magic and the Header and Metadata records (profile ros2, libmcap 0.8.0, ROS_DISTRO humble);
- the first KEPT_CHUNKS chunks' records (every Schema, Channel and Message record inside them, and each chunk's
  times, size and uncompressed CRC, which libmcap 0.8.0 left 0: none), each chunk stored zstd-compressed instead of
  uncompressed: decompressing it gives back the original Chunk record exactly (checked below), so only the chunk's
  compression, compressed size and bytes change;
- the MessageIndex records after those chunks (their offsets are into the uncompressed chunk, so they still hold);
- the summary's Schema and Channel records (all 28 and 42, among them the two of schema encoding 'unknown' with no
  definition, which rosbag2 writes for a type whose definition it could not find) and its MetadataIndex record
  (the Metadata record did not move).
It writes new DataEnd (the data section's CRC), Statistics (of the kept chunks, counted as libmcap counts: the
schemas and channels declared in the data section), ChunkIndex, SummaryOffset and Footer records, as the MCAP
specification defines them.

Usage: python cut_bag.py PATH/mcap_bag_parser-0.3.1.tar.gz
(get the sdist with `pip download --no-deps --no-binary :all: mcap-bag-parser==0.3.1`).
"""
from __future__ import annotations

import hashlib
import io
import struct
import sys
import tarfile
import zlib
from pathlib import Path

import zstandard
from mcap.data_stream import RecordBuilder
from mcap.opcode import Opcode
from mcap.reader import make_reader
from mcap.records import ChunkIndex, DataEnd, Footer, Statistics, SummaryOffset

#: the bag in the sdist and its sha256 (the file the cut was made from)
MEMBER = "mcap_bag_parser-0.3.1/src/mcap_bag/test/bagfile/bagfile_0.mcap"
SOURCE_SHA256 = "492b469e605a05d06b7051e5d938ae27d782e05f9c4d0a75c68dd47b21e9cefa"
#: the first two chunks (0 to 10.2 s of the 42.7 s): every schema of a topic with messages is declared in them, the
#: later eight chunks add two channels and no schema; about 60 kB compressed
KEPT_CHUNKS = 2
#: zstd's level for the kept chunks: its highest regular level (smallest file; the cut is made once)
ZSTD_LEVEL = 19
OUTPUT = Path(__file__).with_name("bagfile_0_cut.mcap")
MAGIC = b"\x89MCAP0\r\n"


def records(data: bytes) -> list[tuple[int, int, int]]:
    """(opcode, start, end) of every top-level record of an MCAP file: end - start = 9 + its content's length."""
    assert data[:8] == MAGIC and data[-8:] == MAGIC, "not an MCAP file"
    found, offset = [], 8
    while offset < len(data) - 8:
        opcode, length = struct.unpack_from("<BQ", data, offset)
        found.append((opcode, offset, offset + 9 + length))
        offset += 9 + length
    return found


def parse_chunk(record: bytes) -> tuple[int, int, int, int, str, bytes]:
    """A Chunk record's fields: message start and end time (ns), uncompressed size and CRC, compression, records."""
    start_ns, end_ns, size, crc = struct.unpack_from("<QQQI", record, 9)
    name_length, = struct.unpack_from("<I", record, 37)
    compression = record[41:41 + name_length].decode()
    data_length, = struct.unpack_from("<Q", record, 41 + name_length)
    data = record[49 + name_length:49 + name_length + data_length]
    return start_ns, end_ns, size, crc, compression, data


def chunk_record(start_ns: int, end_ns: int, size: int, crc: int, compression: str, data: bytes) -> bytes:
    name = compression.encode()
    content = struct.pack("<QQQI", start_ns, end_ns, size, crc) + struct.pack("<I", len(name)) + name \
        + struct.pack("<Q", len(data)) + data
    return struct.pack("<BQ", Opcode.CHUNK, len(content)) + content


def inner_records(data: bytes) -> list[tuple[int, bytes]]:
    """(opcode, content) of the records inside an uncompressed chunk."""
    found, offset = [], 0
    while offset < len(data):
        opcode, length = struct.unpack_from("<BQ", data, offset)
        found.append((opcode, data[offset + 9:offset + 9 + length]))
        offset += 9 + length
    return found


def encoded(record) -> bytes:
    builder = RecordBuilder()
    record.write(builder)
    return builder.end()


def cut(source: bytes) -> bytes:  # noqa: C901 - one branch per MCAP record kind, as the format lists them
    layout = records(source)
    chunks = [k for k, (opcode, _, _) in enumerate(layout) if opcode == Opcode.CHUNK]
    out = bytearray(source[:layout[chunks[0]][1]])        # magic, Header, Metadata
    indexes, schema_ids, channel_ids, counts = [], set(), set(), {}
    for number, k in enumerate(chunks[:KEPT_CHUNKS]):
        _, start, end = layout[k]
        start_ns, end_ns, size, crc, compression, data = parse_chunk(source[start:end])
        assert compression == "" and crc in (0, zlib.crc32(data)) and len(data) == size   # libmcap: CRC 0, none
        packed = zstandard.ZstdCompressor(level=ZSTD_LEVEL).compress(data)
        assert chunk_record(*parse_chunk(chunk_record(start_ns, end_ns, size, crc, "zstd", packed))[:4], "",
                            zstandard.ZstdDecompressor().decompress(packed)) == source[start:end]
        for opcode, content in inner_records(data):
            if opcode == Opcode.SCHEMA:
                schema_ids.add(struct.unpack_from("<H", content)[0])
            elif opcode == Opcode.CHANNEL:
                channel_ids.add(struct.unpack_from("<H", content)[0])
            elif opcode == Opcode.MESSAGE:
                channel_id, = struct.unpack_from("<H", content)
                counts[channel_id] = counts.get(channel_id, 0) + 1
        chunk_start = len(out)
        out += chunk_record(start_ns, end_ns, size, crc, "zstd", packed)
        chunk_length = len(out) - chunk_start
        next_record = chunks[number + 1] if number + 1 < len(chunks) else len(layout)
        index_offsets = {}
        for opcode, index_start, index_end in layout[k + 1:next_record]:
            assert opcode == Opcode.MESSAGE_INDEX
            index_offsets[struct.unpack_from("<H", source, index_start + 9)[0]] = len(out)
            out += source[index_start:index_end]
        indexes.append(ChunkIndex(message_start_time=start_ns, message_end_time=end_ns, chunk_start_offset=chunk_start,
                                  chunk_length=chunk_length, message_index_offsets=index_offsets,
                                  message_index_length=len(out) - chunk_start - chunk_length, compression="zstd",
                                  compressed_size=len(packed), uncompressed_size=size))
    out += encoded(DataEnd(data_section_crc=zlib.crc32(out)))
    summary_start = len(out)
    groups = []
    for opcode in (Opcode.SCHEMA, Opcode.CHANNEL):   # the summary's own records, in its order
        group_start = len(out)
        summary = [(s, e) for o, s, e in layout if o == opcode and s > layout[chunks[-1]][1]]
        for record_start, record_end in summary:
            out += source[record_start:record_end]
        groups.append(SummaryOffset(opcode, group_start, len(out) - group_start))
    metadata_index, = [(s, e) for o, s, e in layout if o == Opcode.METADATA_INDEX]
    metadata, = [(s, e) for o, s, e in layout if o == Opcode.METADATA]
    kept = [indexes[0], indexes[-1]]
    statistics = Statistics(message_count=sum(counts.values()), schema_count=len(schema_ids),
                            channel_count=len(channel_ids), attachment_count=0, metadata_count=1,
                            chunk_count=len(indexes), message_start_time=kept[0].message_start_time,
                            message_end_time=kept[-1].message_end_time, channel_message_counts=counts)
    for opcode, group in ((Opcode.STATISTICS, [encoded(statistics)]),
                          (Opcode.CHUNK_INDEX, [encoded(index) for index in indexes]),
                          (Opcode.METADATA_INDEX, [source[metadata_index[0]:metadata_index[1]]])):
        group_start = len(out)
        for record in group:
            out += record
        groups.append(SummaryOffset(opcode, group_start, len(out) - group_start))
    assert metadata[0] < layout[chunks[0]][1]   # the Metadata record is in the kept prefix: its index holds
    summary_offset_start = len(out)
    for group in groups:
        out += encoded(group)
    footer_fields = struct.pack("<BQQQ", Opcode.FOOTER, 20, summary_start, summary_offset_start)
    out += encoded(Footer(summary_start=summary_start, summary_offset_start=summary_offset_start,
                          summary_crc=zlib.crc32(footer_fields, zlib.crc32(out[summary_start:]))))
    return bytes(out + MAGIC)


def check(path: Path, source: bytes) -> None:
    """The cut reads with the mcap library, CRCs checked: its summary lists the original's schemas and channels, and
    every message of the kept chunks reads back, as many per channel as its statistics say."""
    with open(path, "rb") as stream:
        reader = make_reader(stream, validate_crcs=True)
        summary = reader.get_summary()
        read = {}
        for _, channel, _ in reader.iter_messages():
            read[channel.id] = read.get(channel.id, 0) + 1
    assert summary is not None and summary.statistics is not None
    assert read == summary.statistics.channel_message_counts
    original = make_reader(io.BytesIO(source)).get_summary()
    assert original is not None
    assert summary.schemas == original.schemas and summary.channels == original.channels


def main(argv: list[str]) -> int:
    if len(argv) != 1:
        print(__doc__, file=sys.stderr)
        return 2
    with tarfile.open(argv[0]) as sdist:
        member = sdist.extractfile(MEMBER)
        assert member is not None, f"{argv[0]}: no {MEMBER}"
        source = member.read()
    digest = hashlib.sha256(source).hexdigest()
    if digest != SOURCE_SHA256:
        print(f"{argv[0]}: {MEMBER} has sha256 {digest}, not {SOURCE_SHA256}", file=sys.stderr)
        return 1
    OUTPUT.write_bytes(cut(source))
    check(OUTPUT, source)
    print(f"{OUTPUT}: {OUTPUT.stat().st_size} bytes, sha256 {hashlib.sha256(OUTPUT.read_bytes()).hexdigest()}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
