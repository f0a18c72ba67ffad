"""Files written whole or not at all.

The content goes to NAME.tmp beside the file and is renamed over it once complete (os.replace:
atomic on one file system), so neither a reader nor a run killed half-way ever finds half a file;
on an error the temporary file is removed and the old file, if any, is left as it was. Only the
standard library.
"""
from __future__ import annotations

import os
from contextlib import contextmanager


@contextmanager
def replacing(path):
    """Yields the temporary path (str) to write; when the block ends without an error that file
    replaces `path`, otherwise it is removed. The folder is made if missing."""
    path = os.fspath(path)
    folder = os.path.dirname(path)
    if folder:
        os.makedirs(folder, exist_ok=True)
    tmp = f"{path}.tmp"
    try:
        yield tmp
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)


def write_bytes(path, data: bytes):
    """Writes bytes to path whole; returns path."""
    with replacing(path) as tmp, open(tmp, "wb") as f:
        f.write(data)
    return path


def write_text(path, text: str):
    """Writes text to path whole; returns path."""
    with replacing(path) as tmp, open(tmp, "w") as f:
        f.write(text)
    return path
