#!/usr/bin/python3
"""Digest of a run directory's outputs, for checking that a change keeps every output's bits.

    /usr/bin/python3 scripts/output_digest.py RUN_DIR [RUN_DIR ...]

Prints one line per file: its path relative to RUN_DIR and the SHA-256 of its bytes. Timing
fields of summary.json (wall_time_s and keys holding "seconds" or "wall_time", the thread
count and what the run's thread choice measured, the engine version and build) are dropped before hashing, as are files that record only
timings or the command line (log.txt, run.log, *.png: drawn by matplotlib, whose version may differ).
"""
import hashlib
import json
import sys
from pathlib import Path

SKIP_SUFFIX = (".png",)
SKIP_NAMES = {"log.txt", "run.log"}


def scrub(v):
    if isinstance(v, dict):
        return {k: scrub(x) for k, x in v.items()
                if not ("seconds" in k or "wall_time" in k or k.endswith("_per_s") or k in ("threads", "thread_choice", "version", "build", "command",
                                                                     "engine_version", "build_id", "resume_command"))}
    if isinstance(v, list):
        return [scrub(x) for x in v]
    return v


def digest(path: Path) -> str:
    data = path.read_bytes()
    if path.name.endswith(".json"):
        try:
            data = json.dumps(scrub(json.loads(data)), sort_keys=True).encode()
        except ValueError:
            pass
    return hashlib.sha256(data).hexdigest()[:16]


def main(dirs):
    for d in map(Path, dirs):
        for f in sorted(p for p in d.rglob("*") if p.is_file()):
            if f.suffix in SKIP_SUFFIX or f.name in SKIP_NAMES:
                continue
            print(f"{d.name}/{f.relative_to(d)} {digest(f)}")


if __name__ == "__main__":
    main(sys.argv[1:])
