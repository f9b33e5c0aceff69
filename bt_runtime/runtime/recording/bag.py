"""A rosbag2 bag (version 9, MCAP storage) written in closed segments.

Why segments: a rosbag2 reader (``rosbags``, ``ros2 bag``) trusts ``metadata.yaml`` and a
complete MCAP file (footer and summary). Every ``flush`` closes the current MCAP file and
rewrites ``metadata.yaml`` (atomically) to list it, so a process killed at any moment leaves
a bag that every reader opens, holding everything up to its last flush. Files are named as
``ros2 bag record`` names split bags: ``<bag>_0.mcap``, ``<bag>_1.mcap``...

The MCAP files are written by foxglove-sdk's writer (profile ``ros2``, ``ros2msg`` schemas,
``cdr`` messages, zstd chunks) attached to the recording's ``ChannelSet``; this class opens
and closes them, counts what went in, and writes ``metadata.yaml``.
"""

from __future__ import annotations

import os
import re
from functools import cache
from pathlib import Path
from typing import Any

from .channels import ChannelSet, dump_yaml, offered_qos
from .types import type_hash

# uncompressed bytes per MCAP chunk: a chunk is compressed and written inside the log call that
# fills it, holding the GIL (~1 ms for lz4 at this size); smaller than the SDK's default so that
# pause stays short in a real-time run
CHUNK_SIZE = 256 * 1024


class Rosbag2Bag:
    """Not thread-safe: the writer thread owns it."""

    def __init__(self, path: str | Path, channels: ChannelSet, *, compression: str = "lz4",
                 custom_data: dict[str, str] | None = None):
        self.path = Path(path)
        if self.path.exists() and (not self.path.is_dir() or any(self.path.iterdir())):
            raise FileExistsError(f"{self.path}: exists and is not an empty folder (a bag is never overwritten)")
        self.path.mkdir(parents=True, exist_ok=True)
        self.channels = channels
        self.compression = compression
        self.custom_data = dict(custom_data or {})
        self.counts: dict[str, int] = {}  # per topic, closed segments
        self.files: list[dict[str, Any]] = []  # closed segments
        self.start_ns: int | None = None
        self.end_ns = 0
        self.closed = False
        self._writer: Any = None
        self._seg_path: Path | None = None
        self._seg_counts: dict[str, int] = {}
        self._seg_start = 0
        self._seg_end = 0
        self._rendered: dict[tuple[str, Any], str] = {}  # metadata.yaml entries, rendered once (metadata_yaml)

    @property
    def idle(self) -> bool:
        """No segment open (the next message opens one)."""
        return self._writer is None and not self.closed

    def open_segment(self) -> None:
        """Attach a new MCAP file to the channels (before the first message that goes into it)."""
        if self._writer is not None or self.closed:
            return
        import foxglove
        from foxglove.mcap import MCAPCompression, MCAPWriteOptions

        compression = {"zstd": MCAPCompression.Zstd, "lz4": MCAPCompression.Lz4, "none": None}[self.compression]
        self._seg_path = self.path / f"{self.path.name}_{len(self.files)}.mcap"
        self._writer = foxglove.open_mcap(self._seg_path, context=self.channels.context,
                                          writer_options=MCAPWriteOptions(profile="ros2", compression=compression,
                                                                          compression_threads=0,
                                                                          chunk_size=CHUNK_SIZE))
        self._seg_counts = {}
        self._seg_start, self._seg_end = 2**63 - 1, 0

    def count(self, topic: str, t_ns: int) -> None:
        """One message of ``topic`` goes into the open segment."""
        counts = self._seg_counts
        counts[topic] = counts.get(topic, 0) + 1
        if t_ns < self._seg_start:
            self._seg_start = t_ns
        if t_ns > self._seg_end:
            self._seg_end = t_ns

    def add(self, counts: dict[str, int], start_ns: int, end_ns: int) -> None:
        """A batch of messages went into the open segment: ``counts`` per topic, log times
        ``start_ns..end_ns`` (``count`` for a batch)."""
        seg = self._seg_counts
        for topic, k in counts.items():
            seg[topic] = seg.get(topic, 0) + k
        if start_ns < self._seg_start:
            self._seg_start = start_ns
        if end_ns > self._seg_end:
            self._seg_end = end_ns

    def flush(self) -> None:
        """Close the open segment and list it in metadata.yaml."""
        if self.close_segment():
            self.write_metadata()

    def close_segment(self) -> bool:
        """Close the open segment (its MCAP summary and footer); True when metadata.yaml must be
        rewritten to list it (``write_metadata``: a separate step, so a writer in real time can
        fit each between two ticks)."""
        writer, self._writer = self._writer, None
        if writer is None:
            return False
        writer.close()
        n = sum(self._seg_counts.values())
        if n == 0:
            self._seg_path.unlink(missing_ok=True)
            return False
        self.files.append({"path": self._seg_path.name,
                           "starting_time": {"nanoseconds_since_epoch": self._seg_start},
                           "duration": {"nanoseconds": self._seg_end - self._seg_start},
                           "message_count": n})
        for topic, k in self._seg_counts.items():
            self.counts[topic] = self.counts.get(topic, 0) + k
        self.start_ns = self._seg_start if self.start_ns is None else min(self.start_ns, self._seg_start)
        self.end_ns = max(self.end_ns, self._seg_end)
        return True

    def close(self) -> None:
        if self.closed:
            return
        self.close_segment()
        self.closed = True
        self.write_metadata()  # once: the close's flush wrote it too, for the same content

    def message_counts(self) -> dict[str, int]:
        return dict(self.counts)

    def topic_metadata(self, topic: str) -> dict[str, Any]:
        typename = self.channels.types[topic]
        return {"name": topic, "type": typename, "serialization_format": "cdr",
                "offered_qos_profiles": offered_qos(topic in self.channels.latched),
                "type_description_hash": type_hash(typename)}

    def metadata(self, *, lists: bool = True) -> dict[str, Any]:
        """metadata.yaml's content; ``lists=False``: the lists that grow with the bag (topics,
        files) left empty (``metadata_yaml`` renders their entries once each)."""
        start = self.start_ns or 0
        info = {
            "version": 9,
            "storage_identifier": "mcap",
            "duration": {"nanoseconds": max(0, self.end_ns - start)},
            "starting_time": {"nanoseconds_since_epoch": start},
            "message_count": sum(self.counts.values()),
            "topics_with_message_count": [{"topic_metadata": self.topic_metadata(topic), "message_count": n}
                                          for topic, n in self.counts.items()] if lists else [],
            "compression_format": "",
            "compression_mode": "",
            "relative_file_paths": [f["path"] for f in self.files] if lists else [],
            "files": self.files if lists else [],
            "custom_data": self.custom_data,
            "ros_distro": "jazzy",
        }
        return {"rosbag2_bagfile_information": info}

    def metadata_yaml(self) -> str:
        """``dump_yaml(self.metadata())``, the same text, with each topic's and each segment's
        entry rendered once and kept (the new ones of a call in one dump, each topic's QoS
        profiles once per process): PyYAML's representer is Python even with libyaml's emitter,
        ~2 ms for a bag's 17 topics in one piece, and a segment close in real time holds the GIL
        while it runs (``tests/runtime/recording/test_bag_metadata.py`` compares the texts)."""
        text = dump_yaml(self.metadata(lists=False))
        rendered = self._rendered
        new = [t for t in self.counts if ("topic", t) not in rendered]
        if new:
            metadata = []
            for topic in new:
                entry = self.topic_metadata(topic)
                entry["offered_qos_profiles"] = QOS_MARK
                metadata.append({"topic_metadata": entry, "message_count": 0})
            for topic, entry in zip(new, _render("topics_with_message_count", metadata), strict=True):
                qos = _qos_yaml(topic in self.channels.latched)
                rendered[("topic", topic)] = entry.replace(QOS_LINE, qos).removesuffix("0\n")  # up to its count
        done = sum(1 for f in self.files if ("file", f["path"]) in rendered)
        if done < len(self.files):  # segments are only appended
            for f, path, entry in zip(self.files[done:], _render("relative_file_paths", [f["path"] for f in self.files[done:]]),
                                      _render("files", self.files[done:]), strict=True):
                rendered[("path", f["path"])], rendered[("file", f["path"])] = path, entry
        topics = "".join(rendered[("topic", topic)] + f"{n}\n" for topic, n in self.counts.items())
        paths = "".join(rendered[("path", f["path"])] for f in self.files)
        files = "".join(rendered[("file", f["path"])] for f in self.files)
        for key, entries in (("topics_with_message_count", topics), ("relative_file_paths", paths),
                             ("files", files)):
            if entries:
                text = text.replace(f"\n  {key}: []\n", f"\n  {key}:\n{entries}", 1)
        return text

    def write_metadata(self) -> None:
        tmp = self.path / "metadata.yaml.tmp"
        tmp.write_text(self.metadata_yaml(), encoding="utf-8")
        os.replace(tmp, self.path / "metadata.yaml")


QOS_MARK = "offered-qos-profiles"  # where a topic's entry takes its QoS profiles, rendered once
QOS_LINE = f"      offered_qos_profiles: {QOS_MARK}\n"


def _render(field: str, values: list[Any]) -> list[str]:
    """The YAML lines of each entry of list ``field`` of the bag's information, as ``dump_yaml``
    writes them inside the whole (one dump for all of them)."""
    body = dump_yaml({"rosbag2_bagfile_information": {field: values}}).split("\n", 2)[2]
    return re.split(r"(?m)^(?=  - )", body)[1:]


@cache
def _qos_yaml(latched: bool) -> str:
    """A topic entry's ``offered_qos_profiles`` lines."""
    entry = _render("topics_with_message_count", [{"topic_metadata": {"offered_qos_profiles": offered_qos(latched)}}])[0]
    return entry[entry.index("      offered_qos_profiles:"):]
