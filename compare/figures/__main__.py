"""``python3 -m dem.compare.figures run|network|grid|profiles|bottom|frames|ratios|flow|discharge ...``:
the command line of compare/figures/runs.py."""
from dem.compare.figures.runs import main

if __name__ == "__main__":
    raise SystemExit(main())
