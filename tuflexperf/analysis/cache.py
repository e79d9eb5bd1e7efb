"""Bounded memo of built CasADi problems, keyed on content hashes (never ``repr`` of user data).

A case's free-form provenance (``source:`` in a propulsion file) may hold anything the user
wrote, a YAML anchor bomb included: keys here hash only the numbers the physics reads, so
neither memory nor time depends on it. At most :data:`MAX_ENTRIES` problems per kind stay
built (least recently used dropped first), so a long batch cannot grow without bound.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
from collections import OrderedDict
from collections.abc import Callable
from pathlib import Path
from typing import Any, Generic, TypeVar

T = TypeVar("T")
MAX_ENTRIES = 16
_PROVENANCE = ("metadata", "source")  # free-form: what the user wrote, not what is flown


_KNOWN: OrderedDict[int, tuple[Any, Any]] = OrderedDict()
_KNOWN_SIZE = 256  # frozen model objects whose numbers are kept (each held, so its id stays)


def _physics(obj: Any) -> Any:
    """The numbers of a model object (dataclass / mapping / sequence), provenance left out.

    A frozen dataclass's are kept for the next key that reads it (the case's propulsion is
    read for a dozen problems' keys a command): model objects are never changed in place.
    """
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        frozen = type(obj).__dataclass_params__.frozen  # type: ignore[attr-defined]
        known = _KNOWN.get(id(obj)) if frozen else None
        if known is not None and known[0] is obj:
            return known[1]
        out = {f.name: _physics(getattr(obj, f.name)) for f in dataclasses.fields(obj)
               if f.name not in _PROVENANCE}
        if frozen:
            _KNOWN[id(obj)] = (obj, out)
            while len(_KNOWN) > _KNOWN_SIZE:
                _KNOWN.popitem(last=False)
        return out
    fields = getattr(type(obj), "model_fields", None)  # a validated schema (pydantic)
    if isinstance(fields, dict):
        return {name: _physics(getattr(obj, name)) for name in fields
                if name not in _PROVENANCE}
    if isinstance(obj, dict):
        return {str(k): _physics(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_physics(v) for v in obj]
    if isinstance(obj, (str, int, float, bool)) or obj is None:
        return obj
    return str(type(obj).__name__)  # paths and other handles: not physics


def fingerprint(*parts: Any) -> str:
    """sha256 of the physics content of ``parts`` (aircraft, propulsion, numbers)."""
    text = json.dumps([_physics(p) for p in parts], sort_keys=True, default=str)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def file_key(path: Path) -> tuple[str, float, int]:
    """Which version of a file [path, mtime s, size B]: a file rewritten is a new key."""
    stat = path.stat()
    return (str(path), stat.st_mtime, stat.st_size)


class BoundedCache(Generic[T]):
    """A least-recently-used memo with at most ``size`` entries."""

    def __init__(self, size: int = MAX_ENTRIES) -> None:
        self.size = size
        self._items: OrderedDict[str, T] = OrderedDict()

    def get(self, key: str, build: Callable[[], T]) -> T:
        """The entry for ``key``, built by ``build()`` on first use."""
        if key in self._items:
            self._items.move_to_end(key)
            return self._items[key]
        value = build()
        self._items[key] = value
        while len(self._items) > self.size:
            self._items.popitem(last=False)
        return value

    def __len__(self) -> int:
        return len(self._items)


class ByObject(Generic[T]):
    """What was found for each of the last ``size`` objects asked about, by identity (each
    held, so its id stays); for frozen objects only (the same object, the same answer)."""

    def __init__(self, size: int = 8) -> None:
        self.size = size
        self._items: list[tuple[Any, T]] = []

    def get(self, obj: Any, build: Callable[[], T]) -> T:
        """The answer for ``obj``, built by ``build()`` the first time it is asked about."""
        for held, value in self._items:
            if held is obj:
                return value
        value = build()
        self._items.insert(0, (obj, value))
        del self._items[self.size:]
        return value
