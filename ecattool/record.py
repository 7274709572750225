"""Plain slotted base classes for the model's value objects (what ``@dataclass(slots=True)`` gave, made cheaply).

Creating a slotted dataclass costs ~1 ms at import (generated methods are exec'd, the class is created twice,
``inspect`` builds a docstring), and the ESI/SII models have ~40 of them on every command's path. A
:class:`Record` subclass declares its fields as ``__slots__`` (constructor order) and writes its ``__init__`` by
hand; this base adds what the dataclass added:

* ``==`` — same type (not a subclass) and equal field values in order, like dataclasses' ``eq``;
* ``repr`` — ``Name(field=value, …)``;
* unhashable (``__hash__`` is None, as for a mutable dataclass with ``eq``); :class:`FrozenRecord` is hashable,
  refuses assignment and deletion (:class:`FrozenRecordError`, an ``AttributeError``), and pickles and copies
  through ``__getstate__``/``__setstate__`` (the default restore would use the refused ``setattr``);
* :attr:`Record._fields` (names in order) and :meth:`Record.as_dict` instead of ``dataclasses.fields``/``asdict``.

A class may set ``_fields`` itself (a field kept in a private slot behind a property) and ``_uncompared`` (fields
left out of ``==`` and ``hash``, like ``field(compare=False)``). A frozen record's ``__init__`` assigns through
:data:`set_field` (``object.__setattr__``), as frozen dataclasses do.
"""

from __future__ import annotations

from collections.abc import Callable
from operator import attrgetter
from typing import TYPE_CHECKING, Any, ClassVar

#: how a frozen record's ``__init__`` (and ``__setstate__``) sets its fields
set_field = object.__setattr__


def _no_fields(obj: object) -> tuple[()]:
    return ()


class FrozenRecordError(AttributeError):
    """Assignment to or deletion of a field of a :class:`FrozenRecord` (dataclasses' FrozenInstanceError)."""


class Record:
    """Base of a mutable value object: equality, repr and a field list from ``__slots__``."""

    __slots__ = ()
    #: field names in constructor order: the inherited ones, then the class's own ``__slots__``
    _fields: ClassVar[tuple[str, ...]] = ()
    #: fields that ``==`` and ``hash`` ignore
    _uncompared: ClassVar[tuple[str, ...]] = ()
    #: the compared field values of an instance, as a tuple
    _key: ClassVar[Callable[[Any], Any]] = _no_fields

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if "_fields" not in cls.__dict__:
            own = cls.__dict__.get("__slots__", ())
            cls._fields = (*cls._fields, *((own,) if isinstance(own, str) else own))
        compared = [n for n in cls._fields if n not in cls._uncompared]
        if len(compared) == 1:  # attrgetter of one name gives the bare value; compare tuples as dataclasses do
            one = attrgetter(compared[0])
            cls._key = lambda obj: (one(obj),)
        else:
            cls._key = attrgetter(*compared) if compared else _no_fields

    def __eq__(self, other: object) -> bool:
        if type(other) is not type(self):
            return NotImplemented
        key = type(self)._key
        return bool(key(self) == key(other))

    # defining __eq__ makes instances unhashable (__hash__ = None), as for a dataclass with eq and no frozen

    def __repr__(self) -> str:
        body = ", ".join(f"{n}={getattr(self, n)!r}" for n in self._fields)
        return f"{type(self).__qualname__}({body})"

    def as_dict(self) -> dict[str, Any]:
        """Field name → value, records inside (also in lists, tuples and dicts) converted too (``asdict``)."""
        return {n: _plain(getattr(self, n)) for n in self._fields}


def _plain(v: Any) -> Any:
    if isinstance(v, Record):
        return v.as_dict()
    if isinstance(v, list):
        return [_plain(x) for x in v]
    if isinstance(v, tuple):
        items = [_plain(x) for x in v]
        return type(v)(*items) if hasattr(v, "_fields") else type(v)(items)  # named tuples take arguments
    if isinstance(v, dict):
        return {_plain(k): _plain(x) for k, x in v.items()}
    return v


class FrozenRecord(Record):
    """An immutable, hashable :class:`Record` (what ``@dataclass(frozen=True, slots=True)`` gave)."""

    __slots__ = ()

    def __hash__(self) -> int:
        return hash(type(self)._key(self))

    if not TYPE_CHECKING:  # hidden from mypy, which would otherwise accept assignment to any attribute name

        def __setattr__(self, name: str, value: Any) -> None:
            raise FrozenRecordError(f"cannot assign to field {name!r} of {type(self).__name__}")

        def __delattr__(self, name: str) -> None:
            raise FrozenRecordError(f"cannot delete field {name!r} of {type(self).__name__}")

    def __getstate__(self) -> tuple[Any, ...]:
        return tuple(getattr(self, n) for n in self._fields)

    def __setstate__(self, state: tuple[Any, ...] | list[Any]) -> None:
        # a sequence of field values in order (frozen dataclasses pickled a list of them)
        for name, value in zip(self._fields, state):
            set_field(self, name, value)
