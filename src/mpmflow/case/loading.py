"""Reading a case: the TOML file, `--set` overrides, and errors turned into messages that
name the key and the fix (``CaseError``)."""

import difflib
import json
import re
import sys
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from pydantic import BaseModel, ValidationError

from ..errors import CaseError
from .domain import AXES
from .model import Case
from .reference import _REFERENCE, KNOWN_KEYS, _item, _models_of
from .sections import MAX_CASE_BYTES
from .shapes import SHAPE_TYPES, Body, Obstacle

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib


# --------------------------------------------------------------------------- loading


def _read_toml(path: str | Path) -> dict[str, Any]:
    path = Path(path)
    try:
        with open(path, "rb") as f:  # any file: also a pipe, e.g. <(sed ... case.toml)
            raw = f.read(MAX_CASE_BYTES + 1)
    except FileNotFoundError:
        raise CaseError(
            f"Case file {path} does not exist. Give the path of a .toml case file, "
            "e.g. examples/dam_break.toml."
        ) from None
    except IsADirectoryError:
        raise CaseError(
            f"Case file {path} is a folder; give the path of a .toml case file."
        ) from None
    except OSError as err:
        raise CaseError(f"Case file {path} cannot be read: {err.strerror}.") from None
    if len(raw) > MAX_CASE_BYTES:
        raise CaseError(
            f"Case file {path} is larger than {MAX_CASE_BYTES // 2**20} MiB, so it "
            "is not a case file (a case is a page of TOML text); give the path of "
            "a .toml case file, e.g. examples/dam_break.toml."
        )
    try:  # a byte-order mark (some Windows editors write one) is not part of the TOML
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise CaseError(
            f"Case file {path} is not a UTF-8 text file; give a TOML case file, "
            "e.g. examples/dam_break.toml."
        ) from None
    if "\0" in text:
        raise CaseError(
            f"Case file {path} holds NUL bytes, so it is not a text file; give a "
            "TOML case file, e.g. examples/dam_break.toml."
        )
    try:
        data: dict[str, Any] = tomllib.loads(text)
        return data
    except tomllib.TOMLDecodeError as err:
        raise CaseError(
            f"Case file {path} is not valid TOML: {err}. Fix the syntax there "
            "(strings in quotes, lists in [ ], one key = value per line)."
        ) from None


def _parse_value(text: str) -> Any:
    """A --set value: any TOML value, or a bare word taken as a string."""
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text


# lists of tables an override may replace whole, e.g. {"probes": [{"name": ..., ...}]} or
# --set 'probes=[{name = "p1", quantity = "pressure", position = [0.42, 0.01]}]'
LIST_KEYS = ("bodies", "obstacles", "probes", "inlets", "sponges", "loads")


def _generic(dotted: str) -> str:
    """bodies.0.max -> bodies.N.max"""
    return ".".join("N" if part.isdigit() else part for part in dotted.split("."))


def _suggest(dotted: str) -> str:
    parts = dotted.split(".")
    if parts[0] not in Case.model_fields:
        # a misspelt section or list ([[obstacle]]): the whole key's nearest match would be
        # some key under it (obstacles.0.min), not the name the user meant
        top = difflib.get_close_matches(parts[0], list(Case.model_fields), n=1, cutoff=0.6)
        fixed = ".".join(top + parts[1:])
        if top and (len(parts) == 1 or _generic(fixed) in KNOWN_KEYS):
            tables = f" ([[{top[0]}]] tables)" if len(parts) == 1 and top[0] in LIST_KEYS else ""
            return f" Did you mean `{fixed}`{tables}?"
    match = difflib.get_close_matches(_generic(dotted), KNOWN_KEYS, n=1, cutoff=0.6)
    if not match:
        return ""
    return f" Did you mean `{match[0].replace('.N.', '.' + _index(dotted) + '.')}`?"


def _index(dotted: str) -> str:
    parts = [p for p in dotted.split(".") if p.isdigit()]
    return parts[0] if parts else "0"


def apply_overrides(data: dict[str, Any], overrides: Iterable[str] | Mapping[str, Any]) -> None:
    """Apply overrides to the raw case dict, in place: ``key=value`` strings (dotted keys,
    TOML values, as --set takes them) or a dict {dotted key: Python value}."""
    if isinstance(overrides, dict):
        items = [(str(k), v, False) for k, v in overrides.items()]
    elif isinstance(overrides, str):
        raise CaseError(
            f'overrides = {overrides!r}: give a list of "key=value" strings or '
            'a dict {"dotted.key": value}, e.g. {"grid.spacing": 0.008}.'
        )
    else:
        items = []
        for item in overrides:
            if not isinstance(item, str) or "=" not in item:
                raise CaseError(
                    f"--set {item!r} is not of the form dotted.key=value, e.g. "
                    "--set grid.spacing=0.008."
                )
            key, text = item.split("=", 1)
            items.append((key, text, True))
    for key, value, parse in items:
        key = key.strip()
        label = "--set" if parse else "override"
        parts = key.split(".")
        node = data
        for depth, part in enumerate(parts[:-1]):
            if isinstance(node, list):
                _check_index(label, key, parts, depth, node, value)
                node = node[int(part)]
            else:  # a list of tables the case file leaves out starts empty
                if parts[: depth + 1] == ["domain", "walls"] and isinstance(node.get(part), str):
                    node[part] = _walls_by_axis(node)  # one side set, the others kept
                node = node.setdefault(part, [] if depth == 0 and part in LIST_KEYS else {})
            if not isinstance(node, (dict, list)):
                raise CaseError(
                    f"{label} {key}: `{'.'.join(parts[: depth + 1])}` is a value, not a "
                    "section." + _suggest(key)
                )
        if isinstance(node, list) and len(parts) == 2:  # a whole table: obstacles.0={...}
            _check_index(label, key, parts, 1, node, value, append=True)
            node[int(parts[1]) : int(parts[1]) + 1] = [
                _parse_value(value.strip()) if parse else value
            ]
            continue
        if _generic(key) not in KNOWN_KEYS and key not in LIST_KEYS:
            raise CaseError(
                f"{label} {key}: unknown case key `{key}`.{_suggest(key)} "
                "Run `mpmflow keys` for the list of keys."
            )
        node[parts[-1]] = _parse_value(value.strip()) if parse else value


def _walls_by_axis(domain: dict[str, Any]) -> dict[str, str]:
    """A single domain.walls condition as the table of its wall axes (a periodic axis has
    none), so that an override of one side keeps the condition of the others."""
    size, periodic = domain.get("size"), domain.get("periodic")
    dim = len(size) if isinstance(size, list) and len(size) in (2, 3) else 3
    periodic = periodic if isinstance(periodic, list) else []
    return {
        AXES[k]: domain["walls"]
        for k in range(dim)
        if not (k < len(periodic) and periodic[k] is True)
    }


def _check_index(
    label: str,
    key: str,
    parts: list[str],
    depth: int,
    entries: Any,
    value: Any,
    append: bool = False,
) -> None:
    """parts[depth] indexes the list ``entries`` (the tables of parts[depth - 1]), or, for a
    whole table (``append``), is the next index; CaseError naming the list otherwise."""
    name, part = ".".join(parts[:depth]), parts[depth]
    n = len(entries)
    if part.isdigit() and (int(part) < n or append and int(part) == n):
        return
    after = ".".join(parts[depth + 1 :])
    shown = value.strip() if isinstance(value, str) else "..."
    table = _TABLE_EXAMPLES.get(name, "{...}")
    if n == 0:
        raise CaseError(
            f"{label} {key}: `{name}` has no entries; add one first, e.g. --set "
            f"'{name}.0={table}', or a [[{name}]] table in the case file."
        )
    example = f"{name}.{n - 1}" + (f".{after}" if after else "")
    more = "" if after else f", or --set '{name}.{n}={table}' to add one"
    raise CaseError(
        f"{label} {key}: `{name}` has {n} entr{'y' if n == 1 else 'ies'}; use an "
        f"index from 0 to {n - 1}, e.g. --set {example}={shown}{more}."
    )


_TABLE_EXAMPLES = {  # a table of each list, for messages
    "bodies": '{type = "box", min = [...], max = [...]}',
    "obstacles": '{type = "box", min = [...], max = [...]}',
    "probes": '{name = "p1", quantity = "pressure", position = [...]}',
}


def _shape_loc(parts: Sequence[str | int]) -> tuple[str, str | None]:
    """(loc without the shape tags pydantic puts after a body's or obstacle's index, the
    shape type of that table or None): ("bodies", 0, "disc", "radius") -> bodies.0.radius."""
    out: list[str | int] = []
    kind: str | None = None
    for p in parts:
        if isinstance(p, str) and p in SHAPE_TYPES and out and isinstance(out[-1], int):
            kind = p
            continue
        if isinstance(p, str) and _UNION_MEMBER.match(p):
            continue  # the member of a union the value was tried as: time.dt.float
        out.append(p)
    return ".".join(str(p) for p in out), kind


# the names pydantic gives the members of a union in an error's loc (time.dt's
# "literal['auto']" and "float"): no case key is named so
_UNION_MEMBER = re.compile(r"^(float|int|bool|str|none|[a-z-]+\[.*\])$")


def _toml(value: Any) -> str:
    """A value as the case file writes it: true, "no", [0.0, -9.81], {name = "p1"}."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):  # escaped as TOML escapes: no line breaks in a message
        text = json.dumps(value, ensure_ascii=False)
        return "".join(
            c if c.isprintable() else f"\\u{ord(c):04x}" if ord(c) < 0x10000 else f"\\U{ord(c):08x}"
            for c in text
        )
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    if isinstance(value, dict):
        keys = [k if re.fullmatch(r"[A-Za-z0-9_-]+", str(k)) else _toml(str(k)) for k in value]
        return "{" + ", ".join(f"{k} = {_toml(v)}" for k, v in zip(keys, value.values())) + "}"
    return repr(value)


def _type_hint(kind: str, value: Any) -> str:
    """Why a value of the wrong TOML type is refused, and how to write it (strict types,
    ``sections.Section``); "" for other errors."""
    number = kind in ("int_type", "float_type")
    if number and isinstance(value, bool):
        return " (true and false are booleans, not numbers: give a number)"
    if number and isinstance(value, str):
        try:
            float(value)
        except ValueError:
            return " (a string is not a number: give a number, without quotes)"
        return f" (in quotes it is a string, not a number: write {value.strip()} without quotes)"
    if kind == "int_type" and isinstance(value, float) and value.is_integer():
        return f" (a whole number: write {int(value)}, without the decimal point)"
    if kind == "bool_type":
        return " (a boolean is true or false, without quotes)"
    if kind == "string_type":
        return " (a string: write it in quotes)"
    return ""


def _shape_keys(kind: str, table: str) -> str:
    models = {"bodies": Body, "obstacles": Obstacle}[table]
    model = _models_of(models)[SHAPE_TYPES.index(kind)]
    return ", ".join(model.model_fields)


def _errors(err: ValidationError) -> list[tuple[str, str | None, Any]]:
    """(loc, shape type, error) of each error, a union's members' errors of the same value
    joined into one (time.dt = "0.001": neither "auto" nor a number)."""
    out: list[tuple[str, str | None, Any]] = []
    for e in err.errors():
        loc, kind = _shape_loc(e["loc"])
        union = any(isinstance(p, str) and _UNION_MEMBER.match(p) for p in e["loc"])
        if union and out and out[-1][0] == loc and out[-1][2].get("union"):
            previous = out[-1][2]
            previous["msg"] = previous["msg"].rstrip(".") + ", or " + e["msg"][0].lower()
            previous["msg"] += e["msg"][1:]
            previous["types"].append(e["type"])
            continue
        out.append((loc, kind, {**e, "union": union, "types": [e["type"]]}))
    return out


def _format_error(err: ValidationError, source: str) -> CaseError:
    lines = []
    for loc, kind, e in _errors(err):
        if e["type"] == "union_tag_invalid":
            given = e.get("input", {}).get("type") if isinstance(e.get("input"), dict) else None
            lines.append(
                f"`{loc}.type` = {given!r} is not a shape: give {loc}.type one of "
                + ", ".join(f'"{t}"' for t in SHAPE_TYPES)
                + ' ("box" when left '
                "out); `mpmflow keys` lists each shape's keys."
            )
            continue
        if e["type"] == "extra_forbidden":
            table = loc.split(".")[0]
            if (
                kind is not None
                and table in ("bodies", "obstacles")
                and _generic(loc) in KNOWN_KEYS
            ):
                lines.append(
                    f'`{loc}` is not a key of a "{kind}" ({table} of type '
                    f'"{kind}" take {_shape_keys(kind, table)}): remove it, or '
                    "set the type of shape it belongs to."
                )
                continue
            lines.append(f"unknown key `{loc}`.{_suggest(loc)}")
            continue
        if e["type"] == "missing":
            desc = _describe(loc)
            lines.append(f"missing key `{loc}`{': ' + desc if desc else ''}")
            continue
        msg = e["msg"].removeprefix("Value error, ").rstrip(".")
        key, entry = loc, ""
        while _generic(key) not in _REFERENCE and key.rsplit(".", 1)[-1].isdigit():
            key = key.rsplit(".", 1)[0]  # an entry of a list value: name the key
            entry = f" (entry {loc[len(key) + 1 :]} of {key})"
        row = _REFERENCE.get(_generic(key))
        if row is not None:
            fix = f" Set a valid value, e.g. {key} = {_example(row)}." if _example(row) else ""
            hint = next(filter(None, (_type_hint(t, e.get("input")) for t in e["types"])), "")
            lines.append(
                f"`{loc}`{entry} = {_toml(e.get('input'))} is not allowed: {msg}{hint}. {key}: "
                f"{row['description']}{fix}"
            )
        elif _is_section(loc) and e["type"] == "model_type":
            lines.append(
                f"`{loc}` = {_toml(e.get('input'))} is not allowed: {loc} is a section; "
                f"write it as a [{loc}] table of keys (`mpmflow keys` lists them)."
            )
        else:
            lines.append(f"{loc}: {msg}." if loc else f"{msg}.")
    head = f"Invalid case {source}: " if source else "Invalid case: "
    return CaseError(
        head + " ".join(lines) + " See the case-file reference, docs/reference.md "
        "(or `mpmflow keys`)."
    )


def _is_section(loc: str) -> bool:
    parts = [p for p in loc.split(".") if not p.isdigit()]
    model: type[BaseModel] = Case
    for part in parts:
        field = model.model_fields.get(part)
        if field is None:
            return False
        models = _models_of(_item(field.annotation)[1])
        if not models:
            return False
        model = models[0]
    return True


def _describe(loc: str) -> str:
    return str(_REFERENCE.get(_generic(loc), {}).get("description", ""))


def _example(row: dict[str, Any]) -> str:
    value = row["example"] if row["example"] is not None else row["default"]
    if value is None:
        return ""
    return (
        f'"{value}"'
        if isinstance(value, str)
        else str(value).lower()
        if isinstance(value, bool)
        else str(value)
    )


def validate(data: Any, source: str = "", base_dir: str | Path | None = None) -> Case:
    """A Case from the case's dict; ``base_dir``: the folder relative paths (mesh files,
    probes' data) start from, the case file's (None: the folder of ``source`` when it names
    a file, else the current folder)."""
    if base_dir is None and source and not source.startswith("("):
        base_dir = str(Path(source).resolve().parent)
    try:
        return Case.model_validate(_plain(data), context={"base_dir": base_dir, "folder": base_dir})
    except ValidationError as err:
        raise _format_error(err, source) from None


def _plain(value: Any) -> Any:
    """A case built in Python as TOML would hold it, so that the strict types take NumPy's
    numbers and arrays and tuples as the numbers and lists they stand for (a NumPy bool
    stays a bool, never a number)."""
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, np.ndarray):
        return _plain(value.tolist())
    if isinstance(value, np.generic):
        return value.item()
    return value


def _folder_of(path: str | Path) -> Path:
    """The folder of a case file, where its relative paths start; the current folder for a
    case that is not a regular file (a pipe such as <(sed ... case.toml))."""
    path = Path(path)
    return path.resolve().parent if path.is_file() else Path.cwd()


def load_case(path: str | Path, overrides: Iterable[str] | Mapping[str, Any] = ()) -> Case:
    """Read, override and validate a case file; raises CaseError with a user message.

    ``overrides``: what --set takes, as a list of "dotted.key=value" strings (TOML values),
    or a dict {"dotted.key": value} of Python values, e.g. {"grid.spacing": 0.008,
    "bodies.0.max": [0.1, 0.2]}. Either way the values pass the same checks as the file's."""
    data = _read_toml(path)
    apply_overrides(data, overrides)
    return validate(data, source=str(path), base_dir=_folder_of(path))


def validate_case(data: Any) -> Case:
    """A case from a dict of sections (as the TOML file would hold them), or a Case to check
    again as a whole (see ``revalidate``); CaseError with a user message."""
    if isinstance(data, Case):
        return revalidate(data)
    if not isinstance(data, dict):
        raise CaseError(f"expected a dict of case sections, got {type(data).__name__}.")
    return validate(data)


def revalidate(case: Case) -> Case:
    """The case validated again as a whole: the cross-field checks (bodies in the domain and
    apart, time step against end, ...) for a case whose fields were changed after loading
    (an assignment checks only its own section). CaseError when it no longer holds."""
    if not isinstance(case, Case):
        raise CaseError(
            f"expected a case (mpmflow.load_case(...)), got {type(case).__name__}; "
            "load one with mpmflow.load_case(path, overrides)."
        )
    return validate(case.model_dump(), source="(changed after loading)", base_dir=case._base_dir)


def resolved(case: Case) -> dict[str, Any]:
    """The fully resolved case as plain data (defaults filled in)."""
    return case.model_dump(mode="json")
