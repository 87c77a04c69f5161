"""The simulated plant's metadata (docs/log-format.md "The simulated plant"): the
identification reads none of it, so its reader takes any value; the bench, whose replays
read it, refuses an invalid value where it loads the log, naming the file and line."""

from __future__ import annotations

import pytest

from jointbench.bench.api_log import as_log
from jointbench.bench.sim.friction import log_substeps, timeconst_for_log
from jointbench.identification.log import LogError, read_log

GOOD = """# jointbench-log: 1
# sample_rate_hz: 100
# kp: 40.0
t,q_m,q,tau_m,q_ref
0.00,0.0,0.0,1.0,0.0
0.01,0.1,0.1,2.0,0.1
0.02,0.2,0.2,3.0,0.2
0.03,0.3,0.3,4.0,0.3
"""


def _write(tmp_path, line: str):
    path = tmp_path / "plant.csv"
    path.write_text(GOOD.replace("# kp: 40.0", line))
    return path


@pytest.mark.parametrize("line, match", [
    ("# friction_timeconst_s: soft", r"plant.csv:3: metadata 'friction_timeconst_s' must be a number"),
    ("# friction_timeconst_s: 2 ms", r"plant.csv:3: metadata 'friction_timeconst_s' must be a plain number .*SI unit s"),
    ("# substeps: 0", r"plant.csv:3: metadata 'substeps' must be positive"),
    ("# substeps: many", r"plant.csv:3: metadata 'substeps' must be a number"),
])
def test_the_bench_refuses_bad_plant_keys_with_the_line(tmp_path, line, match):
    path = _write(tmp_path, line)
    assert read_log(path).meta   # the identification's reader does not read them
    with pytest.raises(LogError, match=match):
        as_log(path)
    with pytest.raises(LogError, match=match):
        as_log(read_log(path))


def test_valid_plant_keys_are_read(tmp_path):
    log = as_log(_write(tmp_path, "# substeps: 4\n# friction_timeconst_s: 0.0014 s"))
    assert log_substeps(log, 1) == 4
    assert timeconst_for_log(log, 0.002)[0] == pytest.approx(0.0014)
    bare = as_log(_write(tmp_path, "# kp: 40.0"))
    assert log_substeps(bare, 3) == 3
    assert timeconst_for_log(bare, 0.002)[0] == 0.002
    # MuJoCo's direct form (<= 0) counts as none
    direct = as_log(_write(tmp_path, "# friction_timeconst_s: -1000"))
    assert timeconst_for_log(direct, 0.002)[0] == 0.002
