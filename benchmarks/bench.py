"""Run nfdepth's speed benchmarks: ``python benchmarks/bench.py [--json FILE] [--quick] [--threads N]``.

``nfdepth bench`` itself (its options, checks and one-line errors); see
:mod:`nfdepth.bench` for what is measured.
"""

from __future__ import annotations

import sys

from nfdepth.cli import main as nfdepth_main


def main(argv=None) -> int:
    return nfdepth_main(["bench", *(sys.argv[1:] if argv is None else argv)])


if __name__ == "__main__":
    sys.exit(main())
