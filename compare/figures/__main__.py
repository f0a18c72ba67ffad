"""``python3 -m compare.figures run|network|profiles|ratios|flow|discharge ...``: compare/figures/runs.py."""
import os
import sys


def _pil(argv):
    return any(a == "--renderer=pil" or (a == "--renderer" and argv[k + 1:k + 2] == ["pil"])
               for k, a in enumerate(argv))


if __name__ == "__main__":
    if _pil(sys.argv[1:]):   # drawn by compare.figures.quick_figures before matplotlib is imported
        os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
        from compare.figures import quick_figures
        _status = quick_figures.main(sys.argv[1:])
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(_status)
    from compare.figures.runs import main
    raise SystemExit(main())
