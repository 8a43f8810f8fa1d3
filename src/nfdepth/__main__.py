"""``python -m nfdepth``: the command line."""

from .cli import main

raise SystemExit(main())
