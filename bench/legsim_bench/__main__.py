"""python -m legsim_bench: the legsim-bench command line (see cli.py)."""
import sys

from .cli import main

sys.exit(main())
