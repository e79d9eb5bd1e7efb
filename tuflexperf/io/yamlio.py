"""Strict YAML reading and pydantic-error formatting shared by every file schema."""

from __future__ import annotations

import collections.abc
import difflib
import re
import typing
from pathlib import Path
from typing import Annotated, Any, TypeVar

import yaml
from pydantic import AfterValidator, BaseModel, ConfigDict, Field, ValidationError

from tuflexperf.errors import InputError

M = TypeVar("M", bound=BaseModel)


def _no_nul(name: str) -> str:
    if "\x00" in name:  # the OS refuses it, with a ValueError that names no key
        raise ValueError("a file name cannot hold a NUL character")
    return name


FileName = Annotated[str, Field(min_length=1), AfterValidator(_no_nul)]
"""A file named in a YAML file (relative to that file)."""

MAX_NAME_CHARS = 200
_BIDI_CONTROLS = ("LRE", "RLE", "LRO", "RLO", "PDF", "LRI", "RLI", "FSI", "PDI")


def _one_printable_line(name: str) -> str:
    import unicodedata

    # names go into comments, CSV headers, XML and C sources: a newline would inject YAML
    # keys into fit's output, an escape make the JSBSim and FMU XML malformed
    if any(unicodedata.category(c) in ("Cc", "Zl", "Zp") for c in name):
        raise ValueError("a name is one line of printable characters (no newline, tab or "
                         "control character)")
    # a bidirectional override shows a name in another order than it is stored (U+202E
    # "Trojan Source" in the exported C and XML)
    if any(unicodedata.bidirectional(c) in _BIDI_CONTROLS for c in name):
        raise ValueError("a name cannot hold a bidirectional text control (U+202A-202E, "
                         "U+2066-2069)")
    if not name.strip():
        raise ValueError("a name cannot be empty")
    if len(name) > MAX_NAME_CHARS:
        raise ValueError(f"a name is at most {MAX_NAME_CHARS} characters, got {len(name)}")
    return name


Name = Annotated[str, AfterValidator(_one_printable_line)]
"""The name of an aircraft, a fan, a battery, a case, a campaign or a mission."""


def _column_safe(name: str) -> str:
    # an engine's name heads columns of the mission's CSV (current_a_<engine>, ...): a comma
    # split them, and the file was then no longer recognised as the mission's own output
    if any(c in name for c in ',"'):
        raise ValueError("an engine's name heads CSV columns: no comma or double quote")
    # and it fills the thrust table's engine cells: a spreadsheet runs a cell that starts
    # with one of these as a formula (CSV injection)
    if name[:1] in ("=", "+", "-", "@"):
        raise ValueError(f"an engine's name fills CSV cells: it cannot start with {name[0]!r} "
                         "(a spreadsheet would run it as a formula)")
    return name


def engine_name_problem(name: str) -> str | None:
    """Why ``name`` cannot name an engine (:data:`EngineName`), or ``None`` if it can."""
    try:
        _column_safe(_one_printable_line(name))
    except ValueError as exc:
        return str(exc)
    return None


EngineName = Annotated[str, Field(min_length=1), AfterValidator(_one_printable_line),
                       AfterValidator(_column_safe)]
"""The name of an engine (fan): one printable line that can head a CSV column."""


class StrictModel(BaseModel):
    """Base schema: unknown keys, wrong types, NaN and infinities are all errors."""

    model_config = ConfigDict(extra="forbid", strict=True, allow_inf_nan=False, frozen=True)


# libyaml's parser where PyYAML was built with it (the wheels are): the same documents and
# errors, parsed in C (a case's four files in ~2 ms instead of ~15 ms)
_SafeLoader: type[yaml.SafeLoader] = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


class _UniqueKeyLoader(_SafeLoader):  # type: ignore[misc,valid-type]
    """SafeLoader that refuses duplicate mapping keys (PyYAML keeps the last one silently)."""


def _construct_unique_mapping(loader: yaml.SafeLoader, node: yaml.MappingNode) -> dict[Any, Any]:
    mapping: dict[Any, Any] = {}
    for key_node, value_node in node.value:
        key = loader.construct_object(key_node, deep=True)
        if not isinstance(key, (str, int, float, bool)) and key is not None:
            raise yaml.constructor.ConstructorError(
                None, None, "a key must be a plain name, not a list or mapping",
                key_node.start_mark,
            )
        if key in mapping:
            raise yaml.constructor.ConstructorError(
                None, None, f"duplicate key {key!r}", key_node.start_mark
            )
        mapping[key] = loader.construct_object(value_node, deep=True)
    return mapping


# YAML 1.1 reads "2.21732e1" (no sign in the exponent) and "1e3" as strings; every number
# the user writes in exponent notation is meant as a float
_UniqueKeyLoader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9][0-9_]*)(?:\.[0-9_]*)?[eE][-+]?[0-9]+$"),
    list("-+0123456789"),
)
_UniqueKeyLoader.add_constructor(
    yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _construct_unique_mapping
)


class AmbiguousNumber(str):
    """A number YAML 1.1 reads other than as plain decimal: ``020`` (octal, 16), ``1:00``
    (base 60, 60), ``0x40`` (hex, 64), ``0b11`` (binary, 3). It stays text: a free-form field
    keeps it as written, and a key that needs a number refuses it, naming the key and the
    reading (``min_flight_time_min: 020`` would be a 16 min limit, a false PASS).
    """

    reading: str

    def problem(self) -> str:
        """What is wrong with it, in the words every refusal of it uses."""
        return (f"{str(self)!r} is no plain decimal number (YAML 1.1 reads it as "
                f"{self.reading}): write it in decimal")


_AMBIGUOUS_NUMBER = re.compile(
    r"^[-+]?(?:0[0-9_]+|0[xX][0-9a-fA-F_]+|0[bB][01_]+|0[oO][0-7_]+"
    r"|[0-9][0-9_]*(?::[0-5]?[0-9])+(?:\.[0-9_]*)?)$"
)
_AMBIGUOUS_TAG = "tag:tuflexperf,2026:ambiguous-number"


def ambiguous_number(text: str) -> AmbiguousNumber | None:
    """``text`` as an :class:`AmbiguousNumber` if YAML 1.1 would read it as a non-decimal
    number, else ``None``."""
    text = text.strip()
    if not _AMBIGUOUS_NUMBER.match(text):
        return None
    try:
        value: Any = yaml.safe_load(text)
    except yaml.YAMLError:
        value = None
    number = AmbiguousNumber(text)
    base = ("hex" if "x" in text.lower() else "binary" if "b" in text.lower()
            else "base 60" if ":" in text else "octal")
    number.reading = (f"{base} {value:g}" if isinstance(value, (int, float))
                      and not isinstance(value, bool) else "text")
    return number


def _construct_ambiguous(loader: yaml.SafeLoader, node: yaml.ScalarNode) -> AmbiguousNumber:
    return ambiguous_number(str(node.value)) or AmbiguousNumber(str(node.value))


def _first(resolver_class: Any, characters: str) -> None:
    """The last implicit resolver added for ``characters`` tried before the others."""
    for character in characters:
        entries = resolver_class.yaml_implicit_resolvers[character]
        entries.insert(0, entries.pop())


_UniqueKeyLoader.add_implicit_resolver(_AMBIGUOUS_TAG, _AMBIGUOUS_NUMBER,
                                       list("-+0123456789"))
_first(_UniqueKeyLoader, "-+0123456789")  # before YAML 1.1's int and float
_UniqueKeyLoader.add_constructor(_AMBIGUOUS_TAG, _construct_ambiguous)


def _explicit(tag: str) -> Any:
    """The constructor of an explicitly tagged number (``!!int 020``): a non-decimal form is
    an :class:`AmbiguousNumber` as when untagged (a tag does not take it past)."""
    standard = _UniqueKeyLoader.yaml_constructors[tag]

    def construct(loader: yaml.SafeLoader, node: yaml.ScalarNode) -> Any:
        if isinstance(node.value, str):
            odd = ambiguous_number(node.value)
            if odd is not None:
                return odd
        return standard(loader, node)

    return construct


for _tag in ("tag:yaml.org,2002:int", "tag:yaml.org,2002:float"):
    _UniqueKeyLoader.add_constructor(_tag, _explicit(_tag))


# written back (a file `fit` rewrites) as the text it was, quoted
def _represent_ambiguous(dumper: yaml.SafeDumper, data: AmbiguousNumber) -> yaml.ScalarNode:
    return dumper.represent_str(str(data))  # libyaml's emitter takes a str, not a subclass


for _dumper in {yaml.SafeDumper, getattr(yaml, "CSafeDumper", yaml.SafeDumper)}:
    _dumper.add_representer(AmbiguousNumber, _represent_ambiguous)


MAX_DOCUMENT_VALUES = 2_000_000
"""Values one YAML file may hold once its aliases are expanded: twice the largest
provenance block (``io.case.MAX_SOURCE_VALUES``), far below an alias bomb (9^10)."""


def count_values(value: Any, limit: int) -> int:
    """Values in a nested mapping/list as written out (aliases counted each time), up to
    just beyond ``limit`` (so a self-referencing or bomb-sized structure stops at once)."""
    count, stack = 0, [value]
    while stack and count <= limit:
        item = stack.pop()
        count += 1
        if isinstance(item, dict):
            stack.extend(item.keys())
            stack.extend(item.values())
        elif isinstance(item, (list, tuple)):
            stack.extend(item)
    return count


def read_yaml(path: Path) -> Any:
    """Parse a YAML file; any problem becomes an :class:`InputError` naming the file."""
    from tuflexperf.io.inputs import check_input_file

    check_input_file(path, "YAML file")
    try:
        text = Path(path).read_text(encoding="utf-8")
    except FileNotFoundError:
        raise InputError(f"{path}: file not found") from None
    except IsADirectoryError:
        raise InputError(f"{path}: is a directory, expected a YAML file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{path}: cannot read: {exc}") from None
    try:
        data = yaml.load(text, Loader=_UniqueKeyLoader)  # noqa: S506 - SafeLoader subclass
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" (line {mark.line + 1})" if mark is not None else ""
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        if "yaml.org,2002:merge" in problem:  # the loader knows plain anchors and aliases only
            problem = ("a merge key '<<' is not read here (anchors and aliases are): write "
                       "the merged keys out")
        raise InputError(f"{path}: invalid YAML{where}: {problem}") from None
    except (ValueError, OverflowError) as exc:  # e.g. an integer of more than 4300 digits
        raise InputError(f"{path}: invalid YAML: a value cannot be read: "
                         f"{str(exc).split(';')[0][:120]}") from None
    except RecursionError:
        raise InputError(f"{path}: invalid YAML: nested too deeply") from None
    # aliases share one object: a 143 kB covariance of 20,000 aliased rows is 4e8 floats
    # (3.2 GB) in the schema's hands before its 6 x 6 check; count first
    if count_values(data, MAX_DOCUMENT_VALUES) > MAX_DOCUMENT_VALUES:
        raise InputError(f"{path}: more than {MAX_DOCUMENT_VALUES:,} values once its anchors "
                         "and aliases are expanded: write the file out plainly")
    return data


def format_location(loc: tuple[Any, ...]) -> str:
    """``('engines', 0, 'coefficients', 'p10')`` -> ``engines[0].coefficients.p10``."""
    text = ""
    for part in loc:
        if isinstance(part, int):
            text += f"[{part}]"
        else:
            text += ("." if text else "") + str(part)
    return text or "(top level)"


def _submodel(annotation: Any) -> type[BaseModel] | None:
    """The pydantic model inside an annotation (``X | None``, ``list[X]``, ``Annotated``)."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    for arg in typing.get_args(annotation):
        found = _submodel(arg)
        if found is not None:
            return found
    return None


def _is_mapping(annotation: Any) -> bool:
    """Whether an annotation (``dict[str, X]``, ``X | None``, ``Annotated``) is a mapping."""
    if typing.get_origin(annotation) in (dict, collections.abc.Mapping):
        return True
    return any(_is_mapping(arg) for arg in typing.get_args(annotation))


def _valid_keys(model: type[BaseModel] | None, loc: tuple[Any, ...]) -> list[str]:
    """The keys the schema accepts at ``loc`` (the location of the offending key)."""
    user_key = False  # the next part is a key the user names (of a dict[str, X] field)
    for part in loc[:-1]:
        if model is None:
            return []
        if isinstance(part, int) or user_key:
            user_key = False
            continue
        field = model.model_fields.get(str(part))
        model = _submodel(field.annotation) if field is not None else None
        user_key = field is not None and _is_mapping(field.annotation)
    return list(model.model_fields) if model is not None else []


def validation_problems(
    path: Path | str, error: ValidationError, model: type[BaseModel] | None = None
) -> list[str]:
    """Every problem of ``error``, one line each naming the file, the key and the reason.

    Unknown keys (misspelt ones) come first, each with the closest valid key at its place;
    a required key that a misspelling left missing beside it is said once, by the
    misspelling ("did you mean"), not a second time as missing.
    """
    errors = sorted(error.errors(), key=lambda e: e["type"] != "extra_forbidden")
    explained: set[tuple[Any, ...]] = set()  # missing keys a misspelling accounts for
    problems = []
    for e in errors:
        loc = tuple(e["loc"])
        if e["type"] == "missing" and loc in explained:
            continue
        problem, meant = _problem(e, errors, model)
        if meant is not None:
            explained.add((*loc[:-1], meant))
        problems.append(f"{path}: {format_location(loc)}: {problem}")
    return problems


def _problem(
    e: Any, errors: list[Any], model: type[BaseModel] | None
) -> tuple[str, str | None]:
    """What is wrong in one pydantic error, and the key a misspelt one most likely meant."""
    kind = e["type"]
    if kind == "extra_forbidden":
        key = str(e["loc"][-1])
        parent = tuple(e["loc"][:-1])
        # a misspelt required key leaves that key missing beside it: the missing one is
        # the likelier meaning ('p12' for a missing 'p11', not the present 'p20')
        missing = [str(m["loc"][-1]) for m in errors
                   if m["type"] == "missing" and tuple(m["loc"][:-1]) == parent]
        close = (difflib.get_close_matches(key, missing, n=1, cutoff=0.3)
                 or difflib.get_close_matches(key, _valid_keys(model, tuple(e["loc"])), n=1))
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        return f"unknown key {key!r}{hint}", (close[0] if close else None)
    if kind == "missing":
        return "required key is missing", None
    if isinstance(e.get("input"), AmbiguousNumber):
        value = e["input"]
        return f"{value.problem()}, e.g. {_decimal_hint(value)}", None
    problem = str(e["msg"]).splitlines()[0].removeprefix("Value error, ")
    value = e.get("input")
    if value is None and "null" not in problem:
        problem += " (got null)"  # YAML's word for it
    elif value is not None and not isinstance(value, (dict, list)):
        shown = value.item() if hasattr(value, "item") else value
        text = repr(shown)
        problem += f" (got {text[:60] + '...' if len(text) > 60 else text})"
    return problem, None


def _decimal_hint(value: str) -> str:
    """What a number written with a leading zero most likely meant (``020`` -> ``20``)."""
    sign = value[0] if value[:1] in "+-" else ""
    digits = value.lstrip("+-")
    if digits.isdigit():
        return sign + (digits.lstrip("0") or "0")
    return "12.5"


# the modules whose schemas are whole files (a ``file_kind``); imported only to name the
# kind of a wrong file, on the error path
_FILE_SCHEMA_MODULES = ("case", "battery", "mission", "campaign", "proptables")


def _file_schemas() -> list[type[BaseModel]]:
    """The schemas of whole files (a ``file_kind``)."""
    import importlib

    for module in _FILE_SCHEMA_MODULES:
        importlib.import_module(f"tuflexperf.io.{module}")
    found = []
    pending = list(StrictModel.__subclasses__())
    while pending:
        cls = pending.pop()
        pending.extend(cls.__subclasses__())
        if "file_kind" in cls.__dict__:
            found.append(cls)
    return found


def _another_kind(data: dict[Any, Any], model: type[BaseModel]) -> str | None:
    """The kind of file ``data`` is when it shares no key with ``model``'s but most with
    another file schema's (an aircraft file given as a mission is named so, not told its
    ``mass_kg`` is an unknown key), else None."""
    keys = {str(k) for k in data} - {"name"}
    if not keys or "file_kind" not in model.__dict__:
        return None
    own = len(keys & set(model.model_fields))
    shared, kind = max(((len(keys & set(cls.model_fields)), cls.file_kind)
                        for cls in _file_schemas() if cls is not model), default=(0, ""))
    # a key or two in common is no match: a propulsion file given to fit shares only
    # fan_area_m2 with a campaign's
    return kind if 2 * shared >= len(keys) and shared >= 3 * own else None


def _article(word: str) -> str:
    return f"{'an' if word[0] in 'aeiou' else 'a'} {word}"


def load_model(path: Path, model: type[M]) -> M:
    """Read a YAML file and validate it against ``model``; errors name file and key."""
    data = read_yaml(path)
    if not isinstance(data, dict):
        raise InputError(f"{path}: expected a mapping of keys at the top level")
    try:
        return model.model_validate(data)
    except ValidationError as exc:
        kind = _another_kind(data, model)
        if kind is not None:
            wanted = model.file_kind  # type: ignore[attr-defined]
            raise InputError(f"{path}: this is {_article(kind)} file, not {_article(wanted)} "
                             f"file (its keys are {_article(kind)} file's)") from None
        raise InputError.of(validation_problems(path, exc, model)) from None
