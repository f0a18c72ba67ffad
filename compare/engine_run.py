"""``python3 -m dem.compare.engine_run``: the entry of ``dem run|ensemble --engine CODE``
(compare/codes/reference_run.py)."""
from dem.compare.codes.reference_run import main

if __name__ == "__main__":
    raise SystemExit(main())
