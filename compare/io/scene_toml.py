"""Scene files (docs/scene.md) as Python dicts: the one TOML writer of the Python side.

- ``value(v)``: the TOML literal of a bool, int, float (``repr``, finite only), str or list
  (numpy scalars too); a dict is an inline table;
- ``dumps(doc, header=..., comments=...)``: a scene dict as TOML text, with tables
  (``[end]``), nested tables (``[materials.sand]``) and arrays of tables (``[[pairs]]``,
  ``[[walls]]``), so that ``tomllib.loads(dumps(doc)) == doc``; optional comments on the key and
  table lines, keyed by dotted path (``"physics.gravity"``, ``"pairs[1]"``, ``"pairs[1].mu"``);
- ``load(path)``: the scene's dict (tomllib); a syntax error names the file;
- ``with_changes(doc, changes, add=..., remove=...)``: a copy with keys changed by dotted path
  (``{"end.time": 0.5, "pairs[0].mu": 0.3}``); a key to change or remove that the scene does
  not have raises KeyError naming it, a key to add that it already has raises ValueError, and so
  does a change of kind (a table for a number, a string for a bool, ...): an edit never silently
  leaves the scene as it was;
- ``rebase_paths(doc, from_dir, to_dir)``: relative file paths (``fill.file``, ``start.from``),
  which the engine reads relative to the scene's folder, rewritten for a scene written elsewhere;
- ``write(path, doc, ...)``: dumps written atomically (``NAME.tmp``, then renamed);
- ``edit(path, changes, out_path, ...)``: load, rebase, change, write.

Paths given in ``changes`` or ``add`` are written as given (relative to the new scene's folder,
or absolute); only the paths the scene already had are rebased.
"""
from __future__ import annotations

import copy
import math
import os
import re
import tomllib
from pathlib import Path

from dem.compare.io import atomic_file

# The keys that hold file paths relative to the scene file's folder (docs/scene.md).
PATH_KEYS = ("fill.file", "start.from")

COMMENT_COLUMN = 33          # a trailing comment starts in this column when the line is shorter
_BARE_KEY = re.compile(r"^[A-Za-z0-9_-]+$")
_INT64 = (-2 ** 63, 2 ** 63 - 1)
_SEGMENT = re.compile(r"^(?P<key>[^\[\]]+)(?:\[(?P<index>-?\d+)\])?$")


# --------------------------------------------------------------------------- values

def _string(s: str) -> str:
    """A TOML basic string: backslash, quote and control characters escaped."""
    out = ['"']
    for ch in s:
        code = ord(ch)
        if ch == "\\":
            out.append("\\\\")
        elif ch == '"':
            out.append('\\"')
        elif ch in "\b\t\n\f\r":
            out.append({"\b": "\\b", "\t": "\\t", "\n": "\\n", "\f": "\\f", "\r": "\\r"}[ch])
        elif code < 0x20 or code == 0x7F:
            out.append(f"\\u{code:04x}")
        else:
            out.append(ch)
    out.append('"')
    return "".join(out)


def key(k: str) -> str:
    """A key as TOML writes it: bare when it can be, else a quoted string."""
    if not isinstance(k, str):
        raise TypeError(f"a TOML key must be a string, found {k!r}")
    return k if _BARE_KEY.match(k) else _string(k)


def _scalar(v):
    """v with numpy scalars and arrays as their Python values (tolist), else v."""
    if type(v).__module__ == "numpy" and hasattr(v, "tolist"):
        return v.tolist()
    return v


def value(v) -> str:
    """The TOML literal of v: bool, int (64-bit), float (repr; NaN and infinities refused), str,
    list or tuple (of these), dict (an inline table); numpy scalars and arrays are their Python
    values."""
    v = _scalar(v)
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        if not _INT64[0] <= v <= _INT64[1]:
            raise ValueError(f"the integer {v} does not fit TOML's 64 bits")
        return str(v)
    if isinstance(v, float):
        if not math.isfinite(v):
            raise ValueError(f"cannot write the non-finite value {v} to a scene")
        return repr(v)
    if isinstance(v, str):
        return _string(v)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{key(k)} = {value(x)}" for k, x in v.items()) + "}"
    raise TypeError(f"no TOML form for {type(v).__name__} {v!r}")


# --------------------------------------------------------------------------- documents

def _is_table_array(v) -> bool:
    return isinstance(v, (list, tuple)) and len(v) > 0 and all(isinstance(x, dict) for x in v)


def _is_table(v) -> bool:
    return isinstance(v, dict)


def _commented(line: str, comment: str | None) -> str:
    if not comment:
        return line
    if "\n" in comment:
        raise ValueError(f"a trailing comment is one line: {comment!r}")
    return f"{line.ljust(COMMENT_COLUMN - 1)} # {comment}" if len(line) < COMMENT_COLUMN - 1 \
        else f"{line}   # {comment}"


def _assignment(k: str, v, comment: str | None) -> list[str]:
    """``k = v`` (an array of arrays one element a line)."""
    v = _scalar(v)
    if isinstance(v, (list, tuple)) and v and all(isinstance(_scalar(x), (list, tuple)) for x in v):
        return [_commented(f"{key(k)} = [", comment)] + [f"  {value(x)}," for x in v] + ["]"]
    return [_commented(f"{key(k)} = {value(v)}", comment)]


def dumps(doc: dict, header: str | None = None, comments: dict | None = None) -> str:
    """A scene dict as TOML text.

    Each table's plain keys come first (in the dict's order), then its sub-tables and arrays of
    tables; a table holding only sub-tables gets no header line of its own (``[materials.sand]``
    without ``[materials]``); an empty table gets its header (``[materials.wall]``). A list of
    dicts is an array of tables (``[[pairs]]``); an array of arrays is written one element a
    line. ``header``: comment lines at the top (without their ``#``). ``comments``: dotted
    path -> a comment at the end of that key's or table's line (``"pairs[0]"`` is the first
    ``[[pairs]]`` line); a path that names nothing in the document raises KeyError."""
    if not isinstance(doc, dict):
        raise TypeError(f"a scene is a dict, found {type(doc).__name__}")
    comments = dict(comments or {})
    used = set()
    lines: list[str] = []
    if header:
        lines += [("# " + ln).rstrip() for ln in header.splitlines()]
    headed = len(lines)      # lines before the first table: no blank line after them

    def note(path):
        if path in comments:
            used.add(path)
            return comments[path]
        return None

    def table(path: str, names: list[str], t: dict, array: bool):
        plain = {k: v for k, v in t.items() if not _is_table(v) and not _is_table_array(v)}
        subs = {k: v for k, v in t.items() if k not in plain}
        head = ".".join(key(n) for n in names)
        if names and (array or plain or not subs):
            if len(lines) > headed:
                lines.append("")
            lines.append(_commented(f"[[{head}]]" if array else f"[{head}]", note(path)))
        elif names and path in comments:
            raise ValueError(f"comment on '{path}': the table has no header line of its own")
        for k, v in plain.items():
            lines.extend(_assignment(k, v, note(f"{path}.{k}" if path else k)))
        for k, v in subs.items():
            sub = f"{path}.{k}" if path else k
            if _is_table(v):
                table(sub, names + [k], v, False)
            else:
                for i, item in enumerate(v):
                    table(f"{sub}[{i}]", names + [k], item, True)

    table("", [], doc, False)
    unused = sorted(set(comments) - used)
    if unused:
        raise KeyError(f"comments on keys the scene does not have: {', '.join(unused)}")
    return "\n".join(lines) + "\n"


def loads(text: str, source: str = "<string>") -> dict:
    """A scene's dict from TOML text; a syntax error names ``source``."""
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise ValueError(f"{source}: TOML syntax error: {e}") from None


def load(path) -> dict:
    """A scene file's dict (tomllib); a missing file or a syntax error names the file."""
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as e:
        raise FileNotFoundError(f"{path}: cannot read the scene: {e.strerror or e}") from None
    return loads(text, str(path))


def write(path, doc: dict, header: str | None = None, comments: dict | None = None) -> Path:
    """Writes dumps(doc) to path atomically (``NAME.tmp`` in the same folder, then renamed)."""
    path = Path(path)
    text = dumps(doc, header=header, comments=comments)
    atomic_file.write_text(path, text)
    return path


# --------------------------------------------------------------------------- edits

class SceneKeyError(KeyError):
    """A dotted key that the scene does not have (its message is the text, not a repr)."""

    def __str__(self):
        return str(self.args[0]) if self.args else ""


def _segments(dotted: str) -> list[tuple[str, int | None]]:
    if not isinstance(dotted, str) or not dotted:
        raise ValueError(f"a key path is a non-empty string, found {dotted!r}")
    out = []
    for part in dotted.split("."):
        m = _SEGMENT.match(part)
        if not m:
            raise ValueError(f"'{dotted}': not a key path (name, name.sub, name[i].sub)")
        out.append((m.group("key"), None if m.group("index") is None else int(m.group("index"))))
    return out


def _kind(v) -> str:
    v = _scalar(v)
    if isinstance(v, bool):
        return "bool"
    if isinstance(v, (int, float)):
        return "number"
    if isinstance(v, str):
        return "string"
    if isinstance(v, dict):
        return "table"
    if _is_table_array(v):
        return "array of tables"
    if isinstance(v, (list, tuple)):
        return "array"
    return type(v).__name__


def _locate(doc: dict, dotted: str, create: bool = False):
    """(container, key) of a dotted key path: the table that holds its last key and that key, or
    for a last segment ``name[i]`` the array of tables and i. KeyError naming the key path where
    it leaves the document (create: missing tables on the way are made)."""
    segs = _segments(dotted)
    node = doc
    walked = []
    for n, (k, index) in enumerate(segs):
        last = n == len(segs) - 1
        here = ".".join(walked + [k])
        if last and index is None:
            return node, k
        if k not in node:
            if not (create and index is None):
                raise SceneKeyError(f"the scene has no '{here}' (looking for '{dotted}')")
            node[k] = {}
        child = node[k]
        if index is not None:
            if not _is_table_array(child):
                raise ValueError(f"'{here}' is a {_kind(child)}, not an array of tables "
                                 f"(looking for '{dotted}')")
            if not -len(child) <= index < len(child):
                raise SceneKeyError(f"the scene has no '{here}[{index}]': '{here}' has "
                                    f"{len(child)} entries (looking for '{dotted}')")
            if last:
                return child, index
            here = f"{here}[{index}]"
            child = child[index]
        if not isinstance(child, dict):
            raise ValueError(f"'{here}' is a {_kind(child)}, not a table (looking for '{dotted}')")
        walked.append(k if index is None else f"{k}[{index}]")
        node = child
    raise AssertionError("unreachable")


def _present(container, k) -> bool:
    return k in container if isinstance(container, dict) else True


def get(doc: dict, dotted: str):
    """The value at a dotted key path; KeyError naming it when the scene does not have it."""
    container, k = _locate(doc, dotted)
    if not _present(container, k):
        raise SceneKeyError(f"the scene has no '{dotted}'")
    return container[k]


def has(doc: dict, dotted: str) -> bool:
    """Whether the scene has the dotted key path."""
    try:
        get(doc, dotted)
        return True
    except (KeyError, ValueError):
        return False


def with_changes(doc: dict, changes: dict | None = None, add: dict | None = None,
                 remove=()) -> dict:
    """A deep copy of doc with ``remove`` (dotted keys) deleted, then ``changes`` (dotted key ->
    new value) set, then ``add`` (dotted key -> value) inserted.

    A key to remove or change that the scene does not have raises KeyError naming it; a change
    to another kind of value (a number for a table, a string for a bool; int and float are both
    numbers) and an added key that the scene already has raise ValueError naming it. Added keys
    create the tables on their way (``add={"discharge": {...}}`` or ``{"output.progress": False}``).
    A whole table may be changed for another table (``{"fill": {...}}``), an entry of an array
    of tables for another (``{"pairs[1]": {...}}``)."""
    out = copy.deepcopy(doc)
    for dotted in ([remove] if isinstance(remove, str) else list(remove)):
        container, k = _locate(out, dotted)
        if not _present(container, k):
            raise SceneKeyError(f"cannot remove '{dotted}': the scene has no such key")
        del container[k]
    for dotted, new in (changes or {}).items():
        container, k = _locate(out, dotted)
        if not _present(container, k):
            raise SceneKeyError(f"cannot change '{dotted}': the scene has no such key")
        old = container[k]
        if _kind(old) != _kind(new) and {_kind(old), _kind(new)} != {"array", "array of tables"}:
            raise ValueError(f"cannot change '{dotted}' from a {_kind(old)} ({old!r}) to a "
                             f"{_kind(new)} ({new!r})")
        container[k] = copy.deepcopy(new)
    for dotted, new in (add or {}).items():
        container, k = _locate(out, dotted, create=True)
        if not isinstance(container, dict):
            raise ValueError(f"cannot add '{dotted}': an entry of an array of tables is changed "
                             "(or the whole array), not added")
        if k in container:
            raise ValueError(f"cannot add '{dotted}': the scene already has it "
                             f"(= {container[k]!r}; change it instead)")
        container[k] = copy.deepcopy(new)
    return out


def parse_assignment(assignment: str) -> tuple[str, object]:
    """(key, value) of ``KEY=VALUE`` as ``dem run --set`` reads it: VALUE as a TOML value (5e-5,
    2, true, [1, 2], "text"), else as a string (velocity_verlet); ``walls.0.material`` is
    ``walls[0].material``. ValueError when there is no ``=``."""
    key, eq, text = assignment.partition("=")
    if not eq or not key:
        raise ValueError(f"--set {assignment}: expected KEY=VALUE (integrator.dt=5e-5)")
    if "\n" in text or "\r" in text:
        raise ValueError(f"--set {assignment}: the value must be one line")
    key = re.sub(r"\.(\d+)(?=\.|$)", r"[\1]", key)
    try:
        parsed = tomllib.loads("v = " + text)
        value = parsed["v"] if list(parsed) == ["v"] else text
    except tomllib.TOMLDecodeError:
        value = text
    return key, value


def with_assignments(doc: dict, assignments) -> dict:
    """A copy of doc with each ``KEY=VALUE`` (parse_assignment) set: a key the scene has is
    changed (with_changes: the same kind of value), one it lacks is added, for the engine's
    reader to accept or refuse as in a file (``dem resolve``)."""
    out = doc
    for a in assignments:
        key, value = parse_assignment(a)
        out = with_changes(out, {key: value}) if has(out, key) else with_changes(out, add={key: value})
    return out if out is not doc else copy.deepcopy(doc)


def rebase_paths(doc: dict, from_dir, to_dir) -> dict:
    """A copy of doc whose relative file paths (PATH_KEYS), read by the engine relative to the
    scene's folder ``from_dir``, name the same files from ``to_dir`` (still relative; absolute
    paths stay as they are)."""
    out = copy.deepcopy(doc)
    src, dst = os.path.realpath(from_dir), os.path.realpath(to_dir)
    if src == dst:
        return out
    for dotted in PATH_KEYS:
        if not has(out, dotted):
            continue
        p = get(out, dotted)
        if not isinstance(p, str) or not p or os.path.isabs(p):
            continue
        container, k = _locate(out, dotted)
        container[k] = os.path.relpath(os.path.join(src, p), dst)
    return out


def edit(path, changes: dict | None, out_path, add: dict | None = None, remove=(),
         header: str | None = None, comments: dict | None = None) -> Path:
    """Writes the scene at ``path`` with the changes (with_changes) to ``out_path``; its relative
    file paths are rebased to ``out_path``'s folder (the values given in changes/add are not).
    Returns out_path."""
    path, out_path = Path(path), Path(out_path)
    doc = rebase_paths(load(path), path.parent, out_path.parent)
    return write(out_path, with_changes(doc, changes, add=add, remove=remove),
                 header=header, comments=comments)
