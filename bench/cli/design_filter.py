"""`jointbench design-filter`: the bandpass design of the paper's eqs. (26)-(29)."""

from __future__ import annotations

import argparse
import json
import math
import sys

from jointbench.bench.cli.common import UsageError, finite, positive

# The library `run` imports, loaded by the dispatcher before it traps the signals.
LIBRARY = ("jointbench.identification.design",)


def add_arguments(f: argparse.ArgumentParser) -> None:
    """The options of `design-filter`."""
    f.add_argument("--f1", type=positive, required=True, help="first mode in Hz")
    f.add_argument("--nd", type=int, required=True, help="highest derivative order")
    f.add_argument("--m", type=int, required=True, help="Butterworth order")
    f.add_argument("--ac", type=finite, default=math.sqrt(2) / 2, help="distortion bound Ac (default sqrt(2)/2)")
    f.add_argument("--rc", type=finite, default=1.0, help="distortion ratio rc (default 1)")
    f.add_argument("--ratio", type=positive, default=6.0, help="wc / w1 (default 6)")
    f.add_argument("--json", action="store_true", help="print the JSON object of docs/cli.md")


def _out_of_range(args: argparse.Namespace, what: str) -> UsageError:
    return UsageError(f"--f1 {args.f1:g} Hz, --ratio {args.ratio:g}: the design is out of "
                      f"floating-point range ({what}); give a first mode a joint can have "
                      "(e.g. 0.1 to 1000 Hz)")


def run(args: argparse.Namespace) -> int:
    """Design the bandpass; print wc, wn, xc, Fs and Ts (text or the JSON object of docs/cli.md)."""
    from jointbench.identification.design import design_bandpass

    try:
        d = design_bandpass(args.f1, nd=args.nd, m=args.m, ac=args.ac, rc=args.rc,
                            ratio=args.ratio)
    except (ZeroDivisionError, OverflowError) as err:
        raise _out_of_range(args, str(err)) from None
    out = {"wc_rad_s": d.wc_rad_s, "wn_rad_s": d.wn_rad_s, "fs_hz": d.fs_hz, "ts_s": d.ts_s,
           "xc": d.xc}
    for key, value in out.items():
        # a design whose numbers overflow or underflow double precision is no design
        if not (math.isfinite(value) and sys.float_info.min <= abs(value) <= 1e300):
            raise _out_of_range(args, f"{key} = {value:g}")
    if args.json:
        print(json.dumps(out, allow_nan=False))
    else:
        print(f"f1 = {args.f1:g} Hz, nd = {args.nd}, m = {args.m}, Ac = {args.ac:.4g}, "
              f"rc = {args.rc:g}, wc = {args.ratio:g} w1")
        print(f"wc = {d.wc_rad_s:.2f} rad/s")
        print(f"wn = {d.wn_rad_s:.2f} rad/s   (eq. 28)")
        print(f"xc = {d.xc:.5f}, Fs = {d.fs_hz:.2f} Hz, Ts = {1000 * d.ts_s:.4f} ms   (eq. 29)")
    return 0
