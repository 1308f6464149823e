"""Turn pydantic validation errors into located ``SourceError``s (file:line:col: path: message).

Shared by the materials library and scenes, so both report problems the same way.
"""

from __future__ import annotations

import typing
from typing import Any

from pydantic import BaseModel, ValidationError

from preform.material import Location
from preform.yamlsource import Document, SourceError

# Parts of a pydantic error location that name a validator or a type, not a key in the data.
_PYDANTIC_NOISE = {"list", "dict", "str", "float", "int", "bool", "literal", "json-or-python"}


def data_path(data: Any, loc: tuple[Any, ...]) -> Location:
    """The part of a pydantic error location that exists in the data.

    Pydantic puts union tags and validator names into ``loc``; they are not in the YAML, so they
    are dropped by walking the data alongside the location. A missing key is kept (so the
    message names the field) and ends the walk.
    """
    path: list[str | int] = []
    node = data
    for part in loc:
        if isinstance(node, dict) and part in node:
            path.append(part)
            node = node[part]
        elif isinstance(node, list) and isinstance(part, int) and 0 <= part < len(node):
            path.append(part)
            node = node[part]
        elif (
            isinstance(node, dict)
            and isinstance(part, str)
            and part not in _PYDANTIC_NOISE
            and not part.startswith(("function-", "tagged-union", "union["))
            and part not in _union_tags(node)
        ):
            path.append(part)
            break
    return tuple(path)


def _union_tags(node: dict[str, Any]) -> set[str]:
    """Values of the mapping that pydantic may use as discriminator tags in a location."""
    return {v for v in node.values() if isinstance(v, str)}


def format_path(path: Location) -> str:
    """``("weave", "matrix", 2, 0)`` → ``weave.matrix[2][0]``."""
    out = ""
    for part in path:
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out += ("." if out else "") + str(part)
    return out


def _fields_at(model: type[BaseModel] | None, loc: tuple[Any, ...]) -> list[str]:
    """The fields of the model at ``loc`` inside ``model`` (a section's, not the top level's;
    a union's members' together; a list index or union tag in ``loc`` leaves them as they are)."""
    models = [model] if model is not None else []
    for part in loc:
        for held in (m.model_fields[part].annotation for m in models if part in m.model_fields):
            models = [m for m in _inner(held) if isinstance(m, type) and issubclass(m, BaseModel)]
            break
    return sorted({name for m in models for name in m.model_fields})


def _inner(annotation: Any) -> list[Any]:
    return [annotation, *(inner for arg in typing.get_args(annotation) for inner in _inner(arg))]


def _message(err: Any, model: type[BaseModel] | None) -> str:
    kind = err.get("type", "")
    if kind == "extra_forbidden":
        field = err["loc"][-1] if err.get("loc") else "?"
        return unknown_field_message(field, _fields_at(model, tuple(err["loc"][:-1])))
    if kind == "missing":
        return "required field is missing"
    if kind == "finite_number":
        # Text such as inf, Infinity, nan or 1e999 reaches the model as a string (YAML's own
        # .inf/.nan are refused by the reader); name what was written.
        shown = err.get("input")
        return (
            f"non-finite number {shown!r} is not allowed; write a finite value (infinities, NaN "
            "and numbers that overflow, such as 1e999, are refused, also when written as text)"
        )
    msg = str(err.get("msg", "invalid value"))
    return msg.removeprefix("Value error, ")


def unknown_field_message(field: Any, allowed: list[str]) -> str:
    """Why ``field`` is refused: the closest of the ``allowed`` fields, or all of them."""
    import difflib  # for the message only: off the path of a good listing

    hint = difflib.get_close_matches(str(field), allowed, n=1)
    if hint:
        return f"unknown field {field!r}; did you mean {hint[0]!r}?"
    return f"unknown field {field!r}" + (f"; allowed fields: {', '.join(allowed)}" * bool(allowed))


def located_errors(
    doc: Document,
    base: Location,
    data: Any,
    exc: ValidationError,
    model: type[BaseModel] | None,
    prefix: str = "",
) -> list[SourceError]:
    """One ``SourceError`` per pydantic error, located in ``doc`` under ``base``."""
    out = []
    for err in exc.errors():
        sub = data_path(data, tuple(err.get("loc", ())))
        label = f"{prefix}.{format_path(sub)}" if prefix and sub else prefix or format_path(sub)
        # an unknown field is shown at its key (the thing to delete); a bad value at the value
        at_key = err.get("type") == "extra_forbidden"
        line, column = doc.locate(base + sub) if at_key else doc.locate_value(base + sub)
        out.append(SourceError(doc.file, line, column, label, _message(err, model)))
    return out
