"""Reading YAML input files and turning what is wrong with them into one-line
:class:`~mrcomm.errors.InputError` messages.

* :func:`read_yaml` — parse a file strictly (duplicate keys are an error, because
  PyYAML would otherwise keep the last one silently) and within limits: at most
  :data:`MAX_YAML_BYTES` (refused unread), :data:`MAX_VALUES` values written out and
  nesting :data:`MAX_DEPTH` levels deep (refused while parsing, before anything is
  built: no file takes more than ~5 s or ~500 MB), and :data:`MAX_NODES` values once
  every alias is expanded (a few hundred bytes of nested aliases can stand for billions
  of values: the "billion laughs"). libyaml (PyYAML's C extension) parses.
* :func:`validation_error` — the first error of a pydantic ``ValidationError`` as
  ``file: [3].location.x: must be a number, got 'abc'``, with "did you mean" for
  unknown keys.
"""

from __future__ import annotations

import typing
from pathlib import Path
from typing import Any

import pydantic
import yaml

from mrcomm.errors import InputError, did_you_mean

#: Largest input file read (bytes): larger ones are refused before anything is parsed.
#: The biggest bundled input is campus1000's tasks (260 kB); the 10,000-robot campus's
#: (docs/SCENARIOS.md) are 2.7 MB.
MAX_YAML_BYTES = 8 * 1024 * 1024
#: Most values (scalars, collections, aliases) a document may write out: counted while
#: it is parsed, before any is built, so that no file takes more than ~5 s or ~500 MB to
#: read or refuse (each value costs ~12 µs to parse and build). A task holds 19 values:
#: the 20,000 tasks of the 10,000-robot campus 380,001, its scenario 110,029.
MAX_VALUES = 400_000
#: Deepest nesting of collections.
MAX_DEPTH = 64
#: Most values a document may hold with its aliases expanded.
MAX_NODES = 1_000_000


class _UniqueKeyLoader(yaml.SafeLoader):
    """SafeLoader that rejects a key given twice in one mapping and documents nested
    deeper than :data:`MAX_DEPTH`."""

    _depth = 0

    def compose_node(self, parent: Any, index: Any) -> Any:
        self._depth += 1
        try:
            if self._depth > MAX_DEPTH:
                mark = self.peek_event().start_mark
                problem = f"nested deeper than {MAX_DEPTH} levels"
                raise yaml.composer.ComposerError(None, None, problem, mark)
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1


def _expanded_size(node: yaml.Node, sizes: dict[int, int]) -> int:
    """How many values ``node`` stands for with every alias expanded (an alias is the
    same node object reached again: counted again, computed once)."""
    known = sizes.get(id(node))
    if known is not None:
        return known
    size = 1
    if isinstance(node, yaml.SequenceNode):
        size += sum(_expanded_size(child, sizes) for child in node.value)
    elif isinstance(node, yaml.MappingNode):
        size += sum(_expanded_size(k, sizes) + _expanded_size(v, sizes) for k, v in node.value)
    sizes[id(node)] = size = min(size, MAX_NODES + 1)
    return size


def _construct_unique_mapping(loader: Any, node: yaml.MappingNode) -> Any:
    loader.flatten_mapping(node)  # merge keys (<<) as SafeLoader does
    pairs = loader.construct_pairs(node, deep=True)
    seen: set[Any] = set()
    for (key, _), (key_node, _) in zip(pairs, node.value, strict=True):
        if key in seen:
            line = key_node.start_mark.line + 1
            raise yaml.constructor.ConstructorError(
                None, None, f"key '{key}' given twice (line {line})", key_node.start_mark
            )
        seen.add(key)
    return dict(pairs)


_UniqueKeyLoader.add_constructor(
    yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG,
    _construct_unique_mapping,
)

#: libyaml's parser (PyYAML's C extension), about 20 times as fast as the pure-Python
#: one; without it the pure-Python loader does the same checks.
_CLoader: Any = getattr(yaml, "CSafeLoader", None)
if _CLoader is not None:

    class _FastUniqueKeyLoader(_CLoader):
        """libyaml's SafeLoader that rejects a key given twice in one mapping (the
        nesting is checked before it composes: :func:`_check_depth`)."""

    _FastUniqueKeyLoader.add_constructor(
        yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _construct_unique_mapping
    )


def _check_shape(text: str, path: Path) -> None:
    """Refuse a document of more than :data:`MAX_VALUES` values or nested deeper than
    :data:`MAX_DEPTH`, from libyaml's event stream (a loop, not a recursion: no depth
    can exhaust a stack here), before anything is built."""
    depth = values = 0
    for event in yaml.parse(text, Loader=_CLoader):
        if isinstance(event, yaml.NodeEvent):
            values += 1
            if values > MAX_VALUES:
                raise InputError(f"more than {MAX_VALUES:,} values: not an input file", file=path)
        if isinstance(event, yaml.SequenceStartEvent | yaml.MappingStartEvent):
            depth += 1
            if depth > MAX_DEPTH:
                problem = f"nested deeper than {MAX_DEPTH} levels"
                mark: Any = event.start_mark
                raise yaml.composer.ComposerError(None, None, problem, mark)
        elif isinstance(event, yaml.SequenceEndEvent | yaml.MappingEndEvent):
            depth -= 1


def read_yaml(path: str | Path, *, field: str | None = None) -> Any:
    """Parse a YAML file; a missing, unreadable or malformed file is an InputError.

    ``field`` names the key that referred to this file (e.g. ``tasks``), so a missing
    file is reported against the field that pointed to it.
    """
    path = Path(path)
    try:
        if path.exists() and not path.is_file() and not path.is_dir():
            raise InputError("not a regular file", file=path, field=field)
        if path.is_file() and path.stat().st_size > MAX_YAML_BYTES:
            limit = MAX_YAML_BYTES // (1024 * 1024)
            raise InputError(f"larger than {limit} MB: not an input file", file=path, field=field)
        text = path.read_text(encoding="utf-8")
        if "\x00" in text:  # valid UTF-8 but no text file
            at = text.index("\x00")
            raise InputError(f"binary data at byte {at}, not YAML text (expected a UTF-8 YAML "
                             "file)", file=path, field=field)  # fmt: skip
    except FileNotFoundError:
        raise InputError("file not found", file=path, field=field) from None
    except IsADirectoryError:
        raise InputError("is a directory, expected a YAML file", file=path, field=field) from None
    except UnicodeDecodeError as err:
        raise InputError(
            f"binary data at byte {err.start}, not YAML text (expected a UTF-8 YAML file)",
            file=path,
            field=field,
        ) from None
    except OSError as err:
        raise InputError(f"cannot read file ({err})", file=path, field=field) from None
    loader: Any = None
    try:
        if _CLoader is not None:
            _check_shape(text, path)
            loader = _FastUniqueKeyLoader(text)
        else:
            loader = _UniqueKeyLoader(text)  # reading the text can already fail
        node = loader.get_single_node()
        if node is None:
            return None
        if _expanded_size(node, {}) > MAX_NODES:
            raise InputError(
                f"more than {MAX_NODES:,} values once its aliases are expanded", file=path
            )
        return loader.construct_document(node)
    except RecursionError:
        raise InputError(f"nested deeper than {MAX_DEPTH} levels", file=path) from None
    except yaml.MarkedYAMLError as err:
        if "maximum nesting depth" in str(err.problem):  # libyaml's own limit (1,000)
            raise InputError(f"nested deeper than {MAX_DEPTH} levels", file=path) from None
        mark = err.problem_mark or err.context_mark
        where = f" (line {mark.line + 1}, column {mark.column + 1})" if mark else ""
        problem = err.problem or err.context or "syntax error"
        raise InputError(f"not valid YAML: {problem}{where}", file=path) from None
    except yaml.YAMLError as err:
        raise InputError(f"not valid YAML: {err}", file=path) from None
    finally:
        if loader is not None:
            loader.dispose()


def format_loc(loc: tuple[int | str, ...]) -> str:
    """``(3, 'location', 'x')`` -> ``[3].location.x``."""
    text = ""
    for part in loc:
        if isinstance(part, int):
            text += f"[{part}]"
        else:
            text += f".{part}" if text else str(part)
    return text


def _models_in(annotation: Any) -> list[type[pydantic.BaseModel]]:
    """Every pydantic model class inside a (possibly nested) type annotation."""
    if isinstance(annotation, type) and issubclass(annotation, pydantic.BaseModel):
        return [annotation]
    found: list[type[pydantic.BaseModel]] = []
    for arg in typing.get_args(annotation):
        found.extend(_models_in(arg))
    return found


def _keys_at(root: Any, loc: tuple[int | str, ...]) -> list[str]:
    """Field names of the model found by walking ``loc`` down from ``root`` (a model
    class or annotation); empty when the walk loses track (then no suggestion)."""
    candidates = _models_in(root)
    for part in loc:
        if isinstance(part, int):
            continue  # a list index: the element type is already among the candidates
        nxt: list[type[pydantic.BaseModel]] = []
        for model in candidates:
            info = model.model_fields.get(part)
            if info is not None:
                nxt.extend(_models_in(info.annotation))
        candidates = nxt
    keys: list[str] = []
    for model in candidates:
        keys.extend(info.alias or name for name, info in model.model_fields.items())
    return keys


_TYPE_WORDS = {
    "float_type": "must be a number",
    "float_parsing": "must be a number",
    "finite_number": "must be a finite number",
    "int_type": "must be an integer",
    "int_parsing": "must be an integer",
    "int_from_float": "must be an integer",
    "string_type": "must be a string",
    "bool_type": "must be true or false",
    "list_type": "must be a list",
    "tuple_type": "must be a list",
    "dict_type": "must be a mapping",
    "model_type": "must be a mapping",
    "model_attributes_type": "must be a mapping",
}


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def validation_error(err: pydantic.ValidationError, *, file: str | Path, root: Any) -> InputError:
    """The first error of ``err`` as a one-line InputError.

    ``root`` is the model class (or annotation such as ``list[TaskModel]``) that was
    validated, used to suggest the intended key for an unknown one.
    """
    first = err.errors(include_url=False)[0]
    loc = tuple(first["loc"])
    kind = first["type"]
    if kind == "extra_forbidden":
        key = str(loc[-1])
        hint = did_you_mean(key, _keys_at(root, loc[:-1]))
        return InputError(f"unknown key '{key}'{hint}", file=file, field=format_loc(loc[:-1]))
    if kind == "missing":
        message = "required key is missing"
    elif kind in _TYPE_WORDS:
        message = f"{_TYPE_WORDS[kind]}, got {_short(first.get('input'))}"
    elif kind == "literal_error":
        expected = str(first.get("ctx", {}).get("expected", ""))
        choices = [c.strip(" '\"") for c in expected.replace(" or ", ",").split(",")]
        got = first.get("input")
        message = f"must be one of {', '.join(c for c in choices if c)}, got {_short(got)}"
        message += did_you_mean(str(got), choices)
    elif kind == "string_too_short":
        message = "must not be empty"
    elif kind == "string_pattern_mismatch":
        pattern = first.get("ctx", {}).get("pattern", "")
        message = f"must match {pattern}, got {_short(first.get('input'))}"
    elif kind == "value_error":
        message = str(first["msg"]).removeprefix("Value error, ")
    elif kind in ("greater_than_equal", "greater_than", "less_than_equal", "less_than"):
        message = f"{str(first['msg']).replace('Input should', 'must')}, got {first['input']}"
    else:
        message = str(first["msg"]).replace("Input should", "must")
    return InputError(message, file=file, field=format_loc(loc))


__all__ = ["format_loc", "read_yaml", "validation_error"]
