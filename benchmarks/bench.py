"""Run nfdepth's speed benchmarks: ``python benchmarks/bench.py [--json FILE] [--quick]``.

The same as ``nfdepth bench``; see :mod:`nfdepth.bench` for what is measured.
"""

from __future__ import annotations

import argparse
import sys

from nfdepth.bench import bench_main


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--json", metavar="FILE", help="write the records as JSON (atomically)")
    parser.add_argument("--quick", action="store_true", help="fewer sizes and rounds (< 60 s)")
    args = parser.parse_args(argv)
    return bench_main(json_path=args.json, quick=args.quick)


if __name__ == "__main__":
    sys.exit(main())
