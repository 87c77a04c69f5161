"""Write docs/examples/drive_raw.csv: a jointbench log rewritten in a drive's own layout, the
example of README "Your own data" (`jointbench import`).

    jointbench simulate --duration 20 --seed 1 --out native.csv
    python docs/examples/make_drive_raw.py native.csv docs/examples/drive_raw.csv

Columns: time_ms (ms, from 12.5), motor_counts (motor encoder, 2^17 counts per turn of the
motor shaft, gear ratio 100), link_deg (link encoder, degrees), current_A (torque constant
0.5 N m/A, motor side), ref_counts (the reference in motor counts); 10 significant digits.
"""

import math
import sys

import numpy as np

from jointbench.identification.log import read_log

N, KT, CPR = 100.0, 0.5, 2**17

log = read_log(sys.argv[1])
counts = N * CPR / (2 * math.pi)
table = np.column_stack([12.5 + 1e3 * log.t, np.round(log.q_m * counts), np.rad2deg(log.q),
                         log.tau_m / (N * KT), log.q_ref * counts])
with open(sys.argv[2], "w") as f:
    f.write("# drive export, axis 1\n")
    f.write("time_ms,motor_counts,link_deg,current_A,ref_counts\n")
    np.savetxt(f, table, delimiter=",", fmt="%.10g")
