"""Importing a ROS bag into jointbench logs (docs/log-format.md section 1.7).

A ROS 2 bag (a `.db3` or `.mcap` file, or its folder with `metadata.yaml`) or a ROS 1 `.bag`
holds `sensor_msgs/JointState` messages: per message a header stamp, the joint names and
their `position`, `velocity` and `effort` arrays. For the axis NAME the log takes
  q      <- NAME's position          (the link side),
  q_m    <- NAME_motor's position     (the motor side),
  tau_m  <- NAME_motor's effort       (joint-side units, or motor side with the gear ratio),
  q_ref  <- NAME's position on the reference topic, when one is given,
each from a topic, a joint name and a field the user may change (`BagSpec`).

Time: the drive samples at a fixed rate and stamps each message with jitter. The stamps s_k
of the main topic are fitted by least squares with a uniform grid t0 + k T (one message per
tick); the log's time is that grid, the values are the messages' own (no interpolation). The
grid is refused when a message is missing (a step over GAP_LIMIT periods), when the stamps
go back, or when a stamp is more than GRID_LIMIT of a period off the grid. The jitter
measured (rms and largest |s_k - t0 - k T|) is stated in the log's metadata. The other topics'
messages are matched to the grid tick nearest their stamp (within GRID_LIMIT of a period).

A survey bag moves each joint in turn while the others are held: identification/bag_survey.py
finds which joints moved and when.

Pure numpy; the bag is read with `rosbags` (the optional extra `jointbench[ros]`), imported
when a bag is read. No file writing (the command line writes with `write_log`).
"""

from __future__ import annotations

import os
from collections import Counter
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from jointbench.identification.log.raw import ImportResult, ImportSpec, RawTable, convert
from jointbench.identification.log.schema import LogError

BAG_SUFFIXES = (".db3", ".mcap", ".bag")
DEFAULT_TOPIC = "/joint_states"
MOTOR_SUFFIX = "_motor"
FIELDS = ("position", "velocity", "effort")
STAMPS = ("header", "receive")
BAG_MOTOR_SIDE = ("q_m", "tau_m")   # q and q_ref are the link joint's positions: joint side
GRID_LIMIT = 0.5      # every stamp within half a period of its tick: the tick is unambiguous
GAP_LIMIT = 1.5       # a step between stamps over 1.5 periods: a message is missing
INSTALL_HINT = "reading a bag needs the optional extra: pip install 'jointbench[ros]'"


def is_bag(path: str | os.PathLike) -> bool:
    """A ROS bag by its name: a .db3, .mcap or .bag file, or a folder with metadata.yaml."""
    p = Path(path)
    return p.suffix.lower() in BAG_SUFFIXES or (p.is_dir() and (p / "metadata.yaml").exists())


@dataclass(frozen=True)
class Source:
    """One signal of the bag: `field` of joint `name` on `topic`."""

    topic: str
    name: str
    field: str

    def __str__(self) -> str:
        return f"{self.topic} '{self.name}'.{self.field}"


@dataclass(frozen=True)
class BagSpec:
    """Where the log's columns are in the bag (None: the default of the module docstring).
    `stamp`: `header` (the message's header stamp, the bag's receive time when it is zero)
    or `receive` (the time the recorder logged it)."""

    topic: str = DEFAULT_TOPIC
    link: str | None = None
    motor: str | None = None
    motor_topic: str | None = None
    torque: str | None = None
    torque_field: str = "effort"
    torque_topic: str | None = None
    reference_topic: str | None = None
    reference: str | None = None
    stamp: str = "header"

    def sources(self, joint: str) -> dict[str, Source]:
        """Log column -> Source for the axis `joint`."""
        motor = self.motor or joint + MOTOR_SUFFIX
        motor_topic = self.motor_topic or self.topic
        out = {"q": Source(self.topic, self.link or joint, "position"),
               "q_m": Source(motor_topic, motor, "position"),
               "tau_m": Source(self.torque_topic or motor_topic, self.torque or motor,
                               self.torque_field)}
        if self.reference_topic:
            out["q_ref"] = Source(self.reference_topic, self.reference or self.link or joint,
                                  "position")
        return out


@dataclass(frozen=True)
class TopicData:
    """The messages of one topic: stamps [ns], joint names, values[field] (messages x names,
    NaN where the message's array is empty), the messages skipped (`_topic_data`)."""

    topic: str
    msgtype: str
    stamps_ns: np.ndarray
    names: tuple[str, ...]
    values: dict[str, np.ndarray]
    skipped: int = 0   # messages of another publisher (names disjoint from these)

    def column(self, source: Source, path: str) -> np.ndarray:
        """The values of `source`; LogError naming the missing name or field."""
        if source.name not in self.names:
            raise LogError(f"topic {self.topic}: no joint '{source.name}' (names: "
                           f"{', '.join(self.names)})", path)
        if source.field not in self.values:
            raise LogError(f"topic {self.topic}: message type {self.msgtype} has no field "
                           f"'{source.field}' (needed for {source})", path)
        x = self.values[source.field][:, self.names.index(source.name)]
        empty = np.flatnonzero(~np.isfinite(x))
        if empty.size:
            raise LogError(f"topic {self.topic}: field '{source.field}' of '{source.name}' is "
                           f"empty or not finite in message {int(empty[0]) + 1} of {len(x)}",
                           path)
        return x


@dataclass(frozen=True)
class TimeGrid:
    """The uniform grid t0 + k T fitted to the stamps of `n` messages and the jitter
    |s_k - t0 - k T| measured, in periods."""

    t0_ns: int
    period: float
    n: int
    jitter_rms: float
    jitter_max: float

    @property
    def rate_hz(self) -> float:
        return 1.0 / self.period

    def describe(self) -> str:
        return (f"uniform grid t0 + k T fitted by least squares to {self.n} stamps: "
                f"T = {1e3 * self.period:.6g} ms ({self.rate_hz:.7g} Hz), jitter rms "
                f"{1e6 * self.jitter_rms * self.period:.0f} us ({100 * self.jitter_rms:.3g} % of "
                f"T), largest {1e6 * self.jitter_max * self.period:.0f} us "
                f"({100 * self.jitter_max:.3g} % of T, at most {100 * GRID_LIMIT:g} %)")


@dataclass(frozen=True)
class Bag:
    """The topics read from a bag file."""

    path: str
    topics: dict[str, TopicData]
    available: dict[str, str]   # every topic of the bag -> its message type

    def topic(self, name: str) -> TopicData:
        if name not in self.topics:
            have = ", ".join(f"{t} ({m})" for t, m in sorted(self.available.items())) or "none"
            raise LogError(f"no topic {name} in the bag (topics: {have})", self.path)
        return self.topics[name]


def _stamp_ns(msg, receive_ns: int, stamp: str) -> int:
    header = getattr(msg, "header", None)
    if stamp == "receive" or header is None:
        return int(receive_ns)
    s = header.stamp
    ns = int(s.sec) * 1_000_000_000 + int(getattr(s, "nanosec", getattr(s, "nsec", 0)))
    return ns if ns > 0 else int(receive_ns)


def _topic_data(path: str, topic: str, msgtype: str, messages, stamp: str) -> TopicData:
    """TopicData of deserialised (receive time, message) pairs. The messages carrying the
    most frequent set of names are kept; those of another publisher on the same topic (names
    disjoint from them, e.g. a gripper's) are skipped and counted; a message sharing only some
    of the names is refused."""
    msgs = []
    for k, (receive_ns, msg) in enumerate(messages, start=1):
        if not hasattr(msg, "name"):
            raise LogError(f"topic {topic}: message type {msgtype} has no joint names "
                           "(field 'name'; expected sensor_msgs/JointState)", path)
        msgs.append((k, receive_ns, msg, tuple(str(n) for n in msg.name)))
    if not msgs:
        raise LogError(f"topic {topic}: no message", path)
    sets = Counter(frozenset(m[3]) for m in msgs)
    main = max(sets, key=sets.__getitem__)   # the first seen among equally frequent sets
    names = next(m[3] for m in msgs if frozenset(m[3]) == main)
    fields = [f for f in FIELDS if hasattr(msgs[0][2], f)]
    rows: dict[str, list[np.ndarray]] = {f: [] for f in fields}
    stamps: list[int] = []
    skipped = 0
    for k, receive_ns, msg, these in msgs:
        if frozenset(these) != main or len(these) != len(names):
            if main.isdisjoint(these):
                skipped += 1
                continue
            raise LogError(f"topic {topic}: message {k} names {', '.join(these)}, the others "
                           f"{', '.join(names)}", path)
        order = [these.index(n) for n in names]
        for f in fields:
            a = np.asarray(getattr(msg, f), dtype=float)
            if a.size == 0:
                a = np.full(len(names), np.nan)
            elif a.size != len(names):
                raise LogError(f"topic {topic}: message {k} has {len(names)} names but "
                               f"{a.size} values in '{f}'", path)
            else:
                a = a[order]
            rows[f].append(a)
        stamps.append(_stamp_ns(msg, receive_ns, stamp))
    return TopicData(topic, msgtype, np.array(stamps, dtype=np.int64), names,
                     {f: np.array(v) for f, v in rows.items()}, skipped)


def read_bag(path: str | os.PathLike, topics: set[str], stamp: str = "header") -> Bag:
    """The `topics` of the bag at `path` (ROS 2 .db3, .mcap or folder; ROS 1 .bag), each
    message deserialised. LogError for what cannot be read (a truncated or foreign file, a
    missing rosbags)."""
    try:
        from rosbags.highlevel import AnyReader
        from rosbags.typesys import Stores, get_typestore
    except ImportError:
        raise LogError(INSTALL_HINT, path) from None
    p = Path(path)
    name = str(path)
    if not p.exists():
        raise LogError("no such file or folder", name)
    ros1 = p.suffix.lower() == ".bag"
    store = get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.ROS2_HUMBLE)
    try:
        with AnyReader([p], default_typestore=store) as reader:
            available = {c.topic: c.msgtype for c in reader.connections}
            data = {}
            for topic in sorted(topics & set(available)):
                conns = [c for c in reader.connections if c.topic == topic]
                msgs = ((t, reader.deserialize(raw, c.msgtype))
                        for c, t, raw in reader.messages(connections=conns))
                data[topic] = _topic_data(name, topic, available[topic], msgs, stamp)
    except LogError:
        raise
    except Exception as err:   # rosbags' readers raise many kinds on a damaged file
        text = " ".join(str(err).split()) or type(err).__name__
        raise LogError(f"cannot read the bag (truncated or not a ROS bag?): {text}",
                       name) from None
    return Bag(name, data, available)


def fit_grid(stamps_ns: np.ndarray, topic: str, path: str) -> TimeGrid:
    """The uniform grid of the stamps (module docstring); LogError when the jitter does not
    allow one, naming the message and its stamp."""
    n = len(stamps_ns)
    if n < 3:
        raise LogError(f"topic {topic}: {n} messages, at least 3 are needed", path)
    s = (stamps_ns - stamps_ns[0]).astype(float) * 1e-9
    ds = np.diff(s)
    back = np.flatnonzero(ds <= 0)
    if back.size:
        k = int(back[0]) + 1
        raise LogError(f"topic {topic}: stamps do not increase at message {k + 1} ({s[k]:.9f} s "
                       f"after {s[k - 1]:.9f} s from the first)", path)
    median = float(np.median(ds))
    gap = np.flatnonzero(ds > GAP_LIMIT * median)
    if gap.size:
        k = int(gap[0]) + 1
        raise LogError(f"topic {topic}: a message is missing before message {k + 1} (a step "
                       f"of {ds[k - 1] / median:.3g} periods at {s[k]:.6f} s); a uniform grid "
                       "needs every sample", path)
    k = np.arange(n, dtype=float)
    T, a = np.polyfit(k, s, 1)
    r = np.abs(s - (a + T * k)) / T
    worst = int(np.argmax(r))
    if r[worst] > GRID_LIMIT:
        raise LogError(f"topic {topic}: stamp jitter {100 * r[worst]:.3g} % of the period at "
                       f"message {worst + 1} ({s[worst]:.6f} s), over {100 * GRID_LIMIT:g} %: "
                       "the samples cannot be placed on a uniform grid (try --stamp receive)",
                       path)
    rms = float(np.sqrt(np.mean(r ** 2)))
    return TimeGrid(int(stamps_ns[0]) + int(round(a * 1e9)), float(T), n, rms, float(r[worst]))


def ticks(grid: TimeGrid, stamps_ns: np.ndarray, topic: str, path: str) -> np.ndarray:
    """The grid tick of each stamp of another topic (within GRID_LIMIT of a period)."""
    x = (stamps_ns - grid.t0_ns).astype(float) * 1e-9 / grid.period
    k = np.round(x)
    off = np.abs(x - k)
    worst = int(np.argmax(off))
    if off[worst] > GRID_LIMIT:
        raise LogError(f"topic {topic}: message {worst + 1} is {100 * off[worst]:.3g} % of a "
                       "period off the main topic's grid", path)
    return k.astype(np.int64)


def _columns(bag: Bag, sources: dict[str, Source], grid: TimeGrid, main: str
             ) -> tuple[dict[str, np.ndarray], int]:
    """The log columns on the main topic's grid, trimmed to the ticks every topic covers;
    and the first tick kept. LogError for a tick missing inside that range."""
    cols: dict[str, np.ndarray] = {}
    spans: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    for col, src in sources.items():
        data = bag.topic(src.topic)
        x = data.column(src, bag.path)
        if src.topic == main:
            k = np.arange(len(x), dtype=np.int64)
        else:
            k = ticks(grid, data.stamps_ns, src.topic, bag.path)
        spans[col] = (k, x)
    lo = max(int(k.min()) for k, _ in spans.values())
    hi = min(int(k.max()) for k, _ in spans.values())
    if hi - lo + 1 < 3:
        raise LogError(f"the topics {', '.join(sorted({s.topic for s in sources.values()}))} "
                       "do not overlap in time", bag.path)
    for col, (k, x) in spans.items():
        keep = (k >= lo) & (k <= hi)
        out = np.full(hi - lo + 1, np.nan)
        idx = k[keep] - lo
        if len(np.unique(idx)) != len(idx):
            raise LogError(f"topic {sources[col].topic}: two messages on one tick of the main "
                           "topic's grid", bag.path)
        out[idx] = x[keep]
        miss = np.flatnonzero(np.isnan(out))
        if miss.size:
            raise LogError(f"topic {sources[col].topic}: no message for tick {lo + int(miss[0])}"
                           f" ({(lo + int(miss[0])) * grid.period:.6f} s after the first stamp "
                           f"of {main})", bag.path)
        cols[col] = out
    return cols, lo


def bag_log(bag: Bag, spec: BagSpec, joint: str, grid: TimeGrid, spec_csv: ImportSpec,
            window: tuple[int, int] | None = None, extra_meta: dict[str, str] | None = None
            ) -> ImportResult:
    """The log of axis `joint` (samples `window` = [i0, i1) of the grid, all by default):
    the columns of `spec` converted as a raw table with `log_import.convert` (the gear ratio
    on the `spec_csv.motor_side` columns, BAG_MOTOR_SIDE by default; the metadata of
    `spec_csv`), with the time method in the metadata."""
    sources = spec.sources(joint)
    cols, lo = _columns(bag, sources, grid, spec.topic)
    n = len(cols["q_m"])
    i0, i1 = (0, n) if window is None else (max(window[0] - lo, 0), min(window[1] - lo, n))
    names = ["t", *cols]
    k = np.arange(i0, i1, dtype=float)
    data = np.column_stack([k * grid.period] + [cols[c][i0:i1] for c in cols])
    raw = RawTable(bag.path, tuple(names), data, np.arange(i0, i1) + lo + 1, ",")
    meta = dict(spec_csv.meta)
    meta.setdefault("joint", joint)
    gear = spec_csv.gear_ratio
    ispec = replace(spec_csv, columns={c: c for c in names}, units={},
                    motor_side=spec_csv.motor_side if gear is not None else (), rate_hz=None,
                    meta=meta)
    result = convert(raw, ispec)
    t_first = (grid.t0_ns + (lo + i0) * grid.period * 1e9) * 1e-9
    log_meta = {**result.log.meta,
                "bag_topics": " ".join(sorted({s.topic for s in sources.values()})),
                "bag_time": f"grid t0 + k T fitted to the {spec.stamp} stamps of {spec.topic}; "
                            f"jitter rms {grid.jitter_rms:.3g} T, max {grid.jitter_max:.3g} T",
                "bag_t0_s": f"{t_first:.9f}", **(extra_meta or {})}
    log = replace(result.log, meta=log_meta)
    skipped = [f"{t}: {bag.topics[t].skipped} messages of another publisher skipped (names "
               "disjoint from these)" for t in sorted({s.topic for s in sources.values()})
               if bag.topics[t].skipped]
    steps = [f"read {bag.path}: {len(sources)} signals, " +
             "; ".join(f"{c} <- {s}" for c, s in sources.items()), *skipped,
             f"t <- {grid.describe()}; samples {lo + i0 + 1} to {lo + i1} of {spec.topic}",
             *[s for s in result.steps[2:] if not s.startswith("t ")]]
    return ImportResult(log, tuple(steps), result.checks, result.warnings)


def topics_needed(spec: BagSpec, joint: str | None) -> set[str]:
    """The topics the import reads."""
    sources = spec.sources(joint or "_")
    return {s.topic for s in sources.values()} | {spec.topic}
