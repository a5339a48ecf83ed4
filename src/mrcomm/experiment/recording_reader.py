"""Reading an MCAP recording back: per-channel message counts and time spans, the
mission summary from ``/result`` and the delivery outcomes per topic from ``/messages``
(what ``mrcomm replay`` prints). A missing, unreadable or non-MCAP file is an
:class:`~mrcomm.errors.InputError`, never a traceback.
"""

from __future__ import annotations

import struct
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import msgspec
from mcap.exceptions import McapError
from mcap.reader import make_reader
from zstandard import ZstdError

from mrcomm.errors import InputError
from mrcomm.experiment.recording import METADATA_NAME, TOPIC_MESSAGES, TOPIC_RESULT
from mrcomm.net.delivery import OUTCOMES, count_keys, has_radio_counts, has_shared_counts

_MAGIC = b"\x89MCAP"
# What a damaged file raises while being read: bad records, failed decompression (zstd;
# lz4 raises RuntimeError), bad JSON, seeks before the start of a truncated file.
_DAMAGE: tuple[type[Exception], ...] = (
    McapError,
    ZstdError,
    RuntimeError,
    msgspec.DecodeError,
    struct.error,
    ValueError,
    OSError,
)


@dataclass
class ChannelStats:
    topic: str
    schema: str
    encoding: str
    count: int = 0
    start: float | None = None  # s, mission time
    end: float | None = None

    def as_dict(self) -> dict[str, Any]:
        return {
            "topic": self.topic,
            "schema": self.schema,
            "encoding": self.encoding,
            "count": self.count,
            "start": self.start,
            "end": self.end,
        }


@dataclass
class RecordingSummary:
    """What a recording holds."""

    path: Path
    channels: list[ChannelStats]
    metadata: dict[str, dict[str, str]] = field(default_factory=dict)
    result: dict[str, Any] | None = None
    #: topic -> outcome -> count, from the /messages channel
    outcomes: dict[str, dict[str, int]] = field(default_factory=dict)

    @property
    def message_count(self) -> int:
        return sum(c.count for c in self.channels)

    def channel(self, topic: str) -> ChannelStats | None:
        return next((c for c in self.channels if c.topic == topic), None)

    def as_dict(self) -> dict[str, Any]:
        return {
            "path": str(self.path),
            "message_count": self.message_count,
            "channels": [c.as_dict() for c in self.channels],
            "metadata": self.metadata,
            "outcomes": self.outcomes,
            "result": self.result,
        }


def read_recording(path: Path) -> RecordingSummary:
    """Read a whole recording once and summarise it."""
    path = Path(path)
    if not path.exists():
        raise InputError("no such file", file=path)
    if not path.is_file():
        raise InputError("not a file", file=path)
    try:
        stream = path.open("rb")
    except OSError as err:
        raise InputError(f"cannot read: {err.strerror or err}", file=path) from None
    with stream:
        if stream.read(len(_MAGIC)) != _MAGIC:
            raise InputError("not an MCAP file (bad magic bytes)", file=path)
        stream.seek(0)
        try:
            return _summarise(path, stream)
        except _DAMAGE as err:
            detail = str(err) or type(err).__name__
            raise InputError(f"corrupt or truncated MCAP file ({detail})", file=path) from None


def _summarise(path: Path, stream: Any) -> RecordingSummary:
    reader = make_reader(stream, validate_crcs=True)
    metadata: dict[str, dict[str, str]] = {}
    for record in reader.iter_metadata():
        metadata[record.name] = dict(record.metadata)
    # Log times are wall-clock from the mission's start (recordings before the
    # Foxglove SDK had mission time itself: no epoch).
    epoch_ns = int(metadata.get(METADATA_NAME, {}).get("epoch_ns", "0"))
    stats: dict[int, ChannelStats] = {}
    outcomes: dict[str, Counter[str]] = {}
    result: dict[str, Any] | None = None
    decode_event = msgspec.json.Decoder(dict[str, Any]).decode
    for schema, channel, message in reader.iter_messages(log_time_order=False):
        st = stats.get(channel.id)
        if st is None:
            name = schema.name if schema is not None else ""
            st = stats[channel.id] = ChannelStats(channel.topic, name, channel.message_encoding)
        t = (message.log_time - epoch_ns) / 1e9
        st.count += 1
        st.start = t if st.start is None else min(st.start, t)
        st.end = t if st.end is None else max(st.end, t)
        if channel.topic == TOPIC_MESSAGES:
            event = decode_event(message.data)
            outcomes.setdefault(str(event["topic"]), Counter())[str(event["outcome"])] += 1
        elif channel.topic == TOPIC_RESULT:
            result = decode_event(message.data)
    # Channels without messages still count (they say what the file could hold).
    summary = reader.get_summary()
    if summary is not None:
        for cid, channel in summary.channels.items():
            if cid not in stats:
                sch = summary.schemas.get(channel.schema_id)
                name = sch.name if sch is not None else ""
                stats[cid] = ChannelStats(channel.topic, name, channel.message_encoding)
    radio = has_radio_counts(outcomes.values())
    shared = has_shared_counts(outcomes.values())
    return RecordingSummary(
        path=path,
        channels=sorted(stats.values(), key=lambda c: c.topic),
        metadata=metadata,
        result=result,
        outcomes={
            topic: {o: counts.get(o, 0) for o in count_keys(radio, shared) if o in OUTCOMES}
            for topic, counts in sorted(outcomes.items())
        },
    )


def recording_label(summary: RecordingSummary) -> str:
    """Configuration label of the recorded run ('?' when unknown)."""
    return summary.metadata.get(METADATA_NAME, {}).get("label", "?")
