"""``python3 -m compare.figures run|network|grid|profiles|bottom|frames|ratios|flow|discharge ...``:
the command line of compare/figures/runs.py."""
from compare.figures.runs import main

if __name__ == "__main__":
    raise SystemExit(main())
