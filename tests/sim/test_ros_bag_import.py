"""`jointbench import BAG`: bench experiments written to ROS bags with rosbags' writer, with the
stamp jitter of a real recording, import to logs whose identification agrees with the same
experiments' CSV logs; a survey bag of three joints gives three logs within the survey's
accuracy bar; bad bags get exit 2 naming what is missing, and nothing is written."""

from __future__ import annotations

import json
import shutil
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("rosbags")

from rosbags.rosbag1 import Writer as Writer1  # noqa: E402
from rosbags.rosbag2 import StoragePlugin, Writer  # noqa: E402
from rosbags.typesys import Stores, get_typestore  # noqa: E402

from jointbench.bench.campaign.robot_survey import ACCURACY_BAR_PCT  # noqa: E402
from jointbench.bench.cli import main  # noqa: E402
from jointbench.bench.sim.experiment import run_experiment  # noqa: E402
from jointbench.identification.bag_import import fit_grid  # noqa: E402
from jointbench.identification.bag_survey import (MOTION_WINDOW_S, motion,  # noqa: E402
                                                  rolling_sd)
from jointbench.identification.identify import identify  # noqa: E402
from jointbench.identification.log import read_log, write_log  # noqa: E402
from jointbench.identification.log.schema import LogError  # noqa: E402
from jointbench.identification.parameters import STIFFNESS_AND_INERTIAS  # noqa: E402

DURATION = 30.0
N = 100.0                 # the prototype's gear ratio: the bag holds the motor side
T0_NS = 1_700_000_000_000_000_000
# A ROS 2 driver's header stamps at a few hundred Hz: Gaussian jitter of 50 us, and 2 % of
# the messages late by an exponential delay of mean 150 us (a scheduler hiccup); the recorder
# receives each message 0.2-0.6 ms after its stamp.
JITTER_SD_S, LATE_SHARE, LATE_MEAN_S = 50e-6, 0.02, 150e-6
PLANT_KEYS = ("substeps", "integrator", "friction_timeconst_s")
GAIN_KEYS = ("kp", "kv", "ki", "tau_max")


def stamps_ns(n: int, period: float, seed: int) -> np.ndarray:
    """Header stamps of n samples at `period` with the jitter above."""
    rng = np.random.default_rng(seed)
    jitter = rng.normal(0.0, JITTER_SD_S, n)
    late = rng.random(n) < LATE_SHARE
    jitter[late] += rng.exponential(LATE_MEAN_S, late.sum())
    return T0_NS + np.round((np.arange(n) * period + jitter) * 1e9).astype(np.int64)


def _store(ros1: bool):
    return get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.ROS2_HUMBLE)


def _joint_state(store, stamp: int, names, position, effort):
    T = store.types
    Time = T["builtin_interfaces/msg/Time"]
    extra = {"seq": 0} if "seq" in T["std_msgs/msg/Header"].__dataclass_fields__ else {}
    header = T["std_msgs/msg/Header"](stamp=Time(sec=int(stamp // 10**9),
                                                 nanosec=int(stamp % 10**9)),
                                      frame_id="", **extra)
    return T["sensor_msgs/msg/JointState"](header=header, name=list(names),
                                           position=np.asarray(position, dtype=float),
                                           velocity=np.zeros(0), effort=np.asarray(effort,
                                                                                   dtype=float))


def write_topics(path: Path, topics: dict[str, list[dict]], stamps: np.ndarray,
                 storage: str = "mcap") -> Path:
    """A bag of JointState messages: topic -> frames, frame k = {name: (position, effort)}
    (effort None: an empty effort array; a frame None: no message) stamped stamps[k],
    received 0.2-0.6 ms later (each topic 50 us after the previous). `TOPIC#TAG` is a second
    publisher on TOPIC. `storage`: mcap or sqlite3 (a ROS 2 folder; its storage file is
    returned) or ros1."""
    ros1 = storage == "ros1"
    store = _store(ros1)
    typ = "sensor_msgs/msg/JointState"
    ser = store.serialize_ros1 if ros1 else store.serialize_cdr
    delay = np.random.default_rng(7).integers(200_000, 600_000, len(stamps))

    def messages(writer, conns):
        for k in range(len(stamps)):
            for i, (topic, frames) in enumerate(topics.items()):
                frame = frames[k]
                if frame is None:
                    continue
                names = list(frame)
                efforts = [frame[n][1] for n in names]
                msg = _joint_state(store, int(stamps[k]), names, [frame[n][0] for n in names],
                                   [] if None in efforts else efforts)
                writer.write(conns[topic.split("#")[0]],
                             int(stamps[k] + delay[k] + 50_000 * i), ser(msg, typ))

    if ros1:
        with Writer1(path) as writer:
            messages(writer, {t: writer.add_connection(t, typ, typestore=store)
                              for t in {t.split("#")[0] for t in topics}})
        return path
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    with Writer(path, version=9, storage_plugin=plugin) as writer:
        messages(writer, {t: writer.add_connection(t, typ, typestore=store)
                          for t in {t.split("#")[0] for t in topics}})
    return path / f"{path.name}.{'mcap' if storage == 'mcap' else 'db3'}"


def write_bag(path: Path, frames: list[dict], stamps: np.ndarray, reference=None,
              storage: str = "mcap") -> Path:
    """`frames` on /joint_states and the `reference` frames {name: position}, if any, on
    /reference (write_topics)."""
    topics = {"/joint_states": frames}
    if reference is not None:
        topics["/reference"] = [{n: (x, None) for n, x in f.items()} for f in reference]
    return write_topics(path, topics, stamps, storage)


def frames_of(log, joint: str, held: dict[str, float] | None = None) -> list[dict]:
    """JointState frames of a log: the link NAME (position q, effort 0) and the motor
    NAME_motor on the motor side (position N q_m, effort tau_m / N); held joints constant."""
    held = held or {}
    out = []
    for k in range(len(log)):
        frame = {joint: (log.q[k], 0.0), f"{joint}_motor": (N * log.q_m[k], log.tau_m[k] / N)}
        for name, angle in held.items():
            frame[name] = (angle, 0.0)
            frame[f"{name}_motor"] = (N * angle, 0.0)
        out.append(frame)
    return out


def ref_frames(q_ref, joint: str = "axis1") -> list[dict]:
    return [{joint: x} for x in q_ref]


def meta_args(log, keys) -> list[str]:
    return [a for k in keys if k in log.meta for a in ("--meta", f"{k}={log.meta[k]}")]


@pytest.fixture(scope="module")
def experiment(tmp_path_factory):
    """The prototype's 30 s experiment, its CSV log read back and the bag's stamps."""
    folder = tmp_path_factory.mktemp("bag")
    log = run_experiment("prototype", duration=DURATION, seed=3).log
    write_log(log, folder / "native.csv")
    return read_log(folder / "native.csv"), stamps_ns(len(log), log.ts, seed=11)


def _import(bag: Path, out: Path, log, *extra: str) -> int:
    return main(["import", str(bag), "--out", str(out), "--joint", "axis1", "--gear-ratio",
                 str(N), "--reference-topic", "/reference", *meta_args(log, GAIN_KEYS),
                 *meta_args(log, PLANT_KEYS), *extra])


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_bag_identifies_as_the_csv_log(experiment, storage, tmp_path, capsys):
    """ROS 2 .mcap and .db3: the same samples on a uniform grid fitted to jittered stamps;
    identify agrees with the CSV log's within 0.1 sigma (measured: 0.033 sigma at most, from
    what the bag does not carry, the encoder resolutions and the torque noise in the CSV's
    metadata, and the grid's period fitted to the stamps)."""
    native, stamps = experiment
    bag = write_bag(tmp_path / "rec", frames_of(native, "axis1"), stamps,
                    ref_frames(native.q_ref), storage)
    assert bag.suffix == (".mcap" if storage == "mcap" else ".db3")
    assert _import(bag, tmp_path / "log.csv", native) == 0
    text = capsys.readouterr().out
    assert "uniform grid t0 + k T fitted by least squares" in text and "jitter rms" in text
    log = read_log(tmp_path / "log.csv")
    assert len(log) == len(native)
    assert "jitter rms" in log.meta["bag_time"]
    assert log.sample_rate_hz == pytest.approx(native.sample_rate_hz, rel=1e-6)
    for name in ("q_m", "q", "tau_m", "q_ref"):
        assert np.allclose(getattr(log, name), getattr(native, name), rtol=1e-12, atol=1e-15)
    for key in GAIN_KEYS + PLANT_KEYS:
        assert log.meta[key] == native.meta[key], key
    a, b = identify(native), identify(log)
    assert a.model == b.model == "joint-motor"
    for k, sigma in a.physical_sigma.items():
        assert abs(b.physical[k] - a.physical[k]) <= 0.1 * sigma, k


def test_ros1_bag_and_rosbag2_folder(experiment, tmp_path):
    """A ROS 1 .bag, and a rosbag2 folder (metadata.yaml) given instead of its file."""
    native, stamps = experiment
    n = 2000
    short = type(native)(t=native.t[:n], q_m=native.q_m[:n], tau_m=native.tau_m[:n],
                         q=native.q[:n], q_ref=native.q_ref[:n], meta=native.meta)
    ros1 = write_bag(tmp_path / "rec.bag", frames_of(short, "axis1"), stamps[:n],
                     ref_frames(short.q_ref), "ros1")
    db3 = write_bag(tmp_path / "rec2", frames_of(short, "axis1"), stamps[:n],
                    ref_frames(short.q_ref), "sqlite3")
    for i, bag in enumerate((ros1, db3.parent)):
        assert _import(bag, tmp_path / f"log{i}.csv", short) == 0
        log = read_log(tmp_path / f"log{i}.csv")
        assert np.allclose(log.q_m, short.q_m, rtol=1e-12) and len(log) == n


def test_motor_and_torque_sensor_on_their_own_topics(experiment, tmp_path):
    """A series-elastic arm: the link encoder on /joint_states (joint-side), the motor on
    /motor_states under its own name (motor side), tau_m from a joint torque sensor's
    effort on /torque_sensor, each topic's messages received at its own time."""
    native, stamps = experiment
    n = 3000
    topics = {"/joint_states": [{"elbow": (native.q[k], None)} for k in range(n)],
              "/motor_states": [{"elbow_rotor": (N * native.q_m[k], 0.0)} for k in range(n)],
              "/torque_sensor": [{"elbow_jts": (0.0, native.tau_m[k])}
                                 for k in range(n)]}
    bag = write_topics(tmp_path / "sea", topics, stamps[:n])
    assert main(["import", str(bag), "--out", str(tmp_path / "log.csv"), "--joint", "elbow",
                 "--motor-topic", "/motor_states", "--motor-name", "elbow_rotor",
                 "--torque-topic", "/torque_sensor", "--torque-name", "elbow_jts",
                 "--gear-ratio", str(N), "--motor-side", "q_m"]) == 0
    log = read_log(tmp_path / "log.csv")
    # the torque sensor is joint side (--motor-side q_m): tau_m as it is, q_m / N
    assert np.allclose(log.q_m, native.q_m[:n], rtol=1e-12)
    assert np.array_equal(log.tau_m, native.tau_m[:n])
    assert np.array_equal(log.q, native.q[:n]) and log.q_ref is None
    assert log.meta["bag_topics"] == "/joint_states /motor_states /torque_sensor"


def test_a_second_publisher_on_the_topic_is_skipped(experiment, tmp_path, capsys):
    """/joint_states shared with a gripper's publisher (its own names, a tenth of the rate):
    its messages are skipped and counted; the arm's are imported as they are."""
    native, stamps = experiment
    n = 2000
    topics = {"/joint_states": frames_of(native, "axis1")[:n],
              "/joint_states#gripper": [{"finger": (0.01, 0.0)} if k % 10 == 3 else None
                                        for k in range(n)]}
    bag = write_topics(tmp_path / "shared", topics, stamps[:n])
    assert main(["import", str(bag), "--out", str(tmp_path / "log.csv"), "--joint", "axis1",
                 "--gear-ratio", str(N)]) == 0
    assert "/joint_states: 200 messages of another publisher skipped" in capsys.readouterr().out
    log = read_log(tmp_path / "log.csv")
    assert len(log) == n and np.array_equal(log.q, native.q[:n])


def test_grid_fit_measures_the_jitter_and_refuses_what_it_cannot_place():
    """The grid's period and the jitter come back from synthetic stamps; a missing message,
    a stamp going back and a jitter over half a period are refused naming the message."""
    period = 1 / 350.87
    s = stamps_ns(5000, period, seed=2)
    grid = fit_grid(s, "/joint_states", "b.mcap")
    assert grid.period == pytest.approx(period, rel=1e-6)
    # the jitter's rms: the Gaussian part and the late messages (mean and sd LATE_MEAN_S)
    rms = np.sqrt(JITTER_SD_S ** 2 + LATE_SHARE * 2 * LATE_MEAN_S ** 2) / period
    assert grid.jitter_rms == pytest.approx(rms, rel=0.15)
    with pytest.raises(LogError, match="a message is missing before message 101"):
        fit_grid(np.delete(s, 100), "/joint_states", "b.mcap")
    back = s.copy()
    back[50] = back[49] - 1
    with pytest.raises(LogError, match="do not increase at message 51"):
        fit_grid(back, "/joint_states", "b.mcap")
    # a clock corrected during the recording: the stamps wander 0.8 T off any uniform grid
    wide = s + np.round(0.8 * period * 1e9 * np.sin(2 * np.pi * np.arange(len(s)) / len(s)))
    wide = wide.astype(np.int64)
    with pytest.raises(LogError, match="stamp jitter .* over 50 %"):
        fit_grid(wide, "/joint_states", "b.mcap")


def test_motion_finds_the_window():
    """Held at a constant encoder reading, then a 4 s sine, then held: the window is the
    sine's; a joint that only flickers by one count did not move."""
    rate = 350.87
    t = np.arange(int(20 * rate)) / rate
    q = np.where((t > 6) & (t < 10), 0.3 * np.sin(2 * np.pi * 2 * (t - 6)), 0.0)
    m = motion("a", q, rate)
    assert m.moved
    assert m.start / rate == pytest.approx(6.0, abs=0.15)
    assert m.stop / rate == pytest.approx(10.0, abs=0.15)
    flicker = np.where(np.arange(len(t)) % 97 == 0, 1e-4, 0.0)
    assert not motion("b", flicker, rate).moved
    assert rolling_sd(np.ones(10), 3) == pytest.approx(np.zeros(10), abs=1e-12)


SURVEY = ("axis4", "axis5", "axis6")
SURVEY_DURATION = 60.0
GAP_S = 3.0


@pytest.fixture(scope="module")
def survey_bag(tmp_path_factory, bench_log):
    """arm6's axes 4-6, each moved in turn for 60 s (seed 1, as `survey --seed 1`) while the
    other two are held at their experiment's angle, 3 s of hold between the moves; the
    controller's references on /reference."""
    folder = tmp_path_factory.mktemp("survey")
    logs = {j: bench_log("arm6", j, duration=SURVEY_DURATION, seed=1) for j in SURVEY}
    period = logs[SURVEY[0]].ts
    gap = int(GAP_S / period)
    held = {j: (logs[j].q[0], logs[j].q_m[0], logs[j].tau_m[0]) for j in SURVEY}
    hold_ref = {j: logs[j].q_ref[0] for j in SURVEY}
    frames: list[dict] = []
    refs: list[dict] = []
    for j in SURVEY:
        log = logs[j]
        rows = [{**{o: (held[o][0], 0.0) for o in SURVEY},
                 **{f"{o}_motor": (N * held[o][1], 0.0) for o in SURVEY}}] * gap
        frames += rows
        refs += [dict(hold_ref)] * gap
        for k in range(len(log)):
            f = {o: (held[o][0], 0.0) for o in SURVEY}
            f.update({f"{o}_motor": (N * held[o][1], 0.0) for o in SURVEY})
            f[j] = (log.q[k], 0.0)
            f[f"{j}_motor"] = (N * log.q_m[k], log.tau_m[k] / N)
            frames.append(f)
            refs.append({**hold_ref, j: log.q_ref[k]})
        held[j] = (log.q[-1], log.q_m[-1], log.tau_m[-1])
        hold_ref[j] = log.q_ref[-1]
    frames += [frames[-1]] * gap
    refs += [dict(hold_ref)] * gap
    bag = write_bag(folder / "survey", frames, stamps_ns(len(frames), period, seed=5), refs)
    starts, k = {}, 0
    for j in SURVEY:   # each experiment's first and last sample time in the bag
        k += gap
        starts[j] = (k * period, (k + len(logs[j]) - 1) * period)
        k += len(logs[j])
    return bag, logs, starts


def test_survey_bag_gives_a_log_per_moved_joint(survey_bag, tmp_path, capsys):
    """Three logs, each joint's window found from the data (its 60 s move, the fade-in's and
    fade-out's quietest part left out), each identified within the survey's accuracy bar
    (K, Jm, JL within 0.5 % of the truth, the bar `survey` holds arm6 to at 60 s)."""
    from jointbench.bench.sim.axes import build_experiment_model

    bag, logs, moves = survey_bag
    out = tmp_path / "logs"
    # the simulator's plant keys, as the CSV logs carry them (the same for the three axes)
    plant = meta_args(logs[SURVEY[0]], PLANT_KEYS)
    assert all(meta_args(logs[j], PLANT_KEYS) == plant for j in SURVEY)
    assert main(["import", str(bag), "--out", str(out), "--survey", "--gear-ratio", str(N),
                 "--reference-topic", "/reference", *plant, "--json"]) == 0
    answer = json.loads(capsys.readouterr().out)
    assert answer["moved"] == list(SURVEY) and answer["held"] == []
    for j in SURVEY:
        log = read_log(out / f"{j}.csv")
        start, stop = (float(x) for x in log.meta["bag_window_s"].split())
        first, last = moves[j]   # the window: the move, its quiet ends trimmed, give or
        edge = MOTION_WINDOW_S / 2 + 0.01   # take half the rolling window
        assert first - edge <= start <= first + 0.5, (j, start, first)
        assert last - 0.5 <= stop <= last + edge, (j, stop, last)
        others = dict(p.split("=") for p in log.meta["locked_config"].split())
        assert sorted(others) == sorted(set(SURVEY) - {j})
        truth = build_experiment_model("arm6", j).truth
        fit = identify(log)
        for name in STIFFNESS_AND_INERTIAS:
            err = 100 * (fit.physical[name] / getattr(truth, name) - 1)
            assert abs(err) <= ACCURACY_BAR_PCT, (j, name, err)


def _bad(tmp_path, capsys, argv) -> str:
    before = set(Path(tmp_path).iterdir())
    assert main(["import", *argv]) == 2
    after = set(Path(tmp_path).iterdir())
    assert after == before, "nothing is written"
    return capsys.readouterr().err


def test_bad_bags_exit_2_naming_what_is_missing(experiment, tmp_path, capsys):
    native, stamps = experiment
    n = 500
    frames = frames_of(native, "axis1")[:n]
    bag = write_bag(tmp_path / "ok", frames, stamps[:n], ref_frames(native.q_ref[:n]))
    work = tmp_path / "work"
    work.mkdir()
    out = str(work / "log.csv")
    base = [str(bag), "--out", out]
    assert "no topic /nope" in _bad(work, capsys, base + ["--joint", "axis1", "--topic", "/nope"])
    assert "no topic /ref2" in _bad(work, capsys, base + ["--joint", "axis1",
                                                          "--reference-topic", "/ref2"])
    err = _bad(work, capsys, base + ["--joint", "axis9"])
    assert "no joint 'axis9'" in err and "axis1_motor" in err
    err = _bad(work, capsys, base + ["--joint", "axis1", "--torque-field", "velocity"])
    assert "field 'velocity' of 'axis1_motor' is empty" in err
    # a topic of another message type: no joint names, no field
    store = get_typestore(Stores.ROS2_HUMBLE)
    other = tmp_path / "other"
    with Writer(other, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        conn = writer.add_connection("/joint_states", "std_msgs/msg/Float64", typestore=store)
        for k in range(10):
            writer.write(conn, T0_NS + k, store.serialize_cdr(
                store.types["std_msgs/msg/Float64"](data=1.0), "std_msgs/msg/Float64"))
    err = _bad(work, capsys, [str(other / "other.mcap"), "--out", out, "--joint", "axis1"])
    assert "std_msgs/msg/Float64 has no joint names" in err
    # truncated files
    for suffix in (".mcap",):
        cut = work.parent / f"cut{suffix}"
        data = bag.read_bytes()
        cut.write_bytes(data[: len(data) // 2])
        err = _bad(work, capsys, [str(cut), "--out", out, "--joint", "axis1"])
        assert "cannot read the bag" in err and str(cut) in err
    db3 = write_bag(tmp_path / "ok3", frames, stamps[:n], None, "sqlite3")
    cut = work.parent / "cut.db3"
    cut.write_bytes(db3.read_bytes()[:4096])
    assert "cannot read the bag" in _bad(work, capsys, [str(cut), "--out", out, "--joint",
                                                        "axis1"])
    # a dropped message
    gap = write_bag(tmp_path / "gap", frames[:200] + frames[201:], np.delete(stamps[:n], 200))
    assert "a message is missing before message 201" in _bad(
        work, capsys, [str(gap), "--out", out, "--joint", "axis1"])
    # no --joint, no --survey; --map on a bag
    assert "--joint NAME" in _bad(work, capsys, base)
    assert "for CSV files" in _bad(work, capsys, base + ["--joint", "axis1", "--map", "t=t"])
    assert "leave out --motor-name" in _bad(work, capsys, base + ["--survey", "--motor-name",
                                                                  "m"])
    # a survey bag where nothing moved: the folder is not created
    still = write_bag(tmp_path / "still", [frames[0]] * 300, stamps[:300])
    err = _bad(work, capsys, [str(still), "--out", str(work / "logs"), "--survey"])
    assert "no joint moved" in err
    shutil.rmtree(work)


def test_without_rosbags_the_extra_is_named(experiment, tmp_path, monkeypatch, capsys):
    """rosbags missing: exit 2 naming the extra to install, nothing written."""
    native, stamps = experiment
    bag = write_bag(tmp_path / "b", frames_of(native, "axis1")[:100], stamps[:100])
    monkeypatch.setitem(sys.modules, "rosbags.highlevel", None)   # import fails
    work = tmp_path / "w"
    work.mkdir()
    err = _bad(work, capsys, [str(bag), "--out", str(work / "log.csv"), "--joint", "axis1"])
    assert "pip install 'jointbench[ros]'" in err
