"""Stage layouts declared once: each stage's packed float64 buffer as one ``Layout``.

A stage's state crosses from Python into numba packed (``kernel_layout.Packed``): a small
NamedTuple of scalars and one float64 buffer holding all its arrays. A ``Layout`` is the one
declaration of that buffer: its fields in buffer order, each with its length (or shape), and
the NamedTuple the kernels read them through. From it come

- the stage's ``unpack_*`` kernel (``Layout.unpacker``): an ``@njit(inline="always")``
  function, generated from the declaration, that returns the NamedTuple of views of the
  buffer (and the layout's length). It is compiled and cached like a hand-written one
  (its code object names the stage's module, so numba's cache and ``jit_cache``'s digest
  treat it as that module's);
- the buffer's length for given dimensions (``Layout.size``);
- the offset of a field (``Layout.offset``), for the flags a kernel reads by slot.

A field's length is an ``int``, a shape (a tuple, the view is reshaped), a ``Dim`` (linear
in the stage's dimensions, e.g. ``2 * N`` for a residual over n joints) or a nested
``Layout`` (its fields follow in the buffer and build a nested NamedTuple). A NamedTuple
field the layout does not hold is the unpack's argument of that name if there is one, else
that attribute of the unpack's second argument (the stage's scalars): ``ImpedanceParams``'
``k_null`` is ``sc.k_null``.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Union

from numba import njit

from impact_control.errors import InvalidArgumentError


@dataclass(frozen=True)
class Dim:
    """A length linear in named dimensions: ``const + sum(coef * dim)`` (elements)."""

    const: int = 0
    coefs: tuple[tuple[str, int], ...] = ()

    @staticmethod
    def named(name: str) -> Dim:
        """The dimension ``name`` (bound by a ``Layout``'s ``dims``)."""
        return Dim(0, ((name, 1),))

    @staticmethod
    def of(value: int | Dim) -> Dim:
        """``value`` as a ``Dim``."""
        return value if isinstance(value, Dim) else Dim(int(value))

    def __add__(self, other: int | Dim) -> Dim:
        other = Dim.of(other)
        coefs = dict(self.coefs)
        for name, k in other.coefs:
            coefs[name] = coefs.get(name, 0) + k
        return Dim(self.const + other.const, tuple((n, k) for n, k in coefs.items() if k))

    __radd__ = __add__

    def __mul__(self, k: int) -> Dim:
        return Dim(self.const * k, tuple((n, c * k) for n, c in self.coefs))

    __rmul__ = __mul__

    def __sub__(self, other: int | Dim) -> Dim:
        return self + (-1) * Dim.of(other)

    def value(self, dims: Mapping[str, int]) -> int:
        """The length for the dimensions ``dims``."""
        missing = sorted({n for n, _ in self.coefs} - set(dims))
        if missing:
            raise InvalidArgumentError(f"layout length needs dimension(s) {missing}; "
                                       f"given {sorted(dims)}")
        return self.const + sum(k * int(dims[n]) for n, k in self.coefs)

    def source(self) -> str:
        """Python source of the length (dimension ``n`` is the local ``dim_n``)."""
        terms = [f"{k} * dim_{n}" if k != 1 else f"dim_{n}" for n, k in self.coefs]
        if self.const or not terms:
            terms.append(str(self.const))
        return " + ".join(terms)


LAYOUTS: dict[str, tuple[Layout, Any]] = {}
"""Every generated unpack, by ``module.name``: (its layout, its plain-Python function).
Filled as the stage modules import (tests/control/test_stage_layout.py walks it)."""

N_JOINTS = Dim.named("n")
"""The arm's joint count, the dimension most stages are laid out over (bound as ``n``)."""

def slots(names: str) -> dict[str, int]:
    """One (1,) field per whitespace-separated name: a stage's constants and scalar state,
    kept in its buffer (a view crosses into numba cheaper than many scalars)."""
    return dict.fromkeys(names.split(), 1)


def _shape_length(shape: tuple[int | Dim, ...]) -> Dim:
    """Elements of an array of ``shape`` (at most one entry a ``Dim``: lengths stay linear)."""
    dims = [d for d in shape if isinstance(d, Dim)]
    if len(dims) > 1:
        raise InvalidArgumentError(f"shape {shape}: at most one dimension may be a Dim")
    ints = math.prod(d for d in shape if not isinstance(d, Dim))
    return dims[0] * ints if dims else Dim(ints)


def _shape_source(shape: tuple[int | Dim, ...]) -> str:
    """Python source of ``shape`` as a reshape argument."""
    return "(" + ", ".join(d.source() if isinstance(d, Dim) else str(d) for d in shape) + ",)"


FieldSize = Union[int, tuple[int | Dim, ...], Dim, "Layout"]
"""A field's length (module docstring)."""


@dataclass(frozen=True)
class Layout:
    """One stage's float64 buffer: ``fields`` in buffer order, read as ``state``.

    Attributes:
        state: The NamedTuple class the unpack returns.
        fields: (name, length) in buffer order (module docstring: the kinds of length).
        dims: (dimension, Python expression of the unpack's arguments) bound before the
            fields, e.g. ``("n", "sc.n_joints")``.
        args: The unpack's arguments; the first is the buffer.
    """

    state: type
    fields: tuple[tuple[str, FieldSize], ...]
    dims: tuple[tuple[str, str], ...] = ()
    args: tuple[str, ...] = ("buf", "sc")

    @staticmethod
    def of(state: type, fields: Mapping[str, FieldSize], *, dims: Mapping[str, str] | None = None,
           args: tuple[str, ...] = ("buf", "sc")) -> Layout:
        """A layout from a mapping of fields (its order is the buffer's)."""
        return Layout(state, tuple(fields.items()), tuple((dims or {}).items()), args)

    def flat(self, prefix: str = "") -> list[tuple[str, Dim, tuple[int | Dim, ...] | None]]:
        """(local name, length, shape or None) of every array, in buffer order."""
        out: list[tuple[str, Dim, tuple[int | Dim, ...] | None]] = []
        for name, size in self.fields:
            if isinstance(size, Layout):
                out.extend(size.flat(f"{prefix}{name}__"))
            elif isinstance(size, tuple):
                out.append((prefix + name, _shape_length(size), size))
            else:
                out.append((prefix + name, Dim.of(size), None))
        return out

    @property
    def length(self) -> Dim:
        """The buffer's length, linear in the dimensions."""
        return sum((d for _, d, _ in self.flat()), Dim())

    def size(self, **dims: int) -> int:
        """The buffer's length for the dimensions ``dims`` (``Layout.dims``' names)."""
        return self.length.value(dims)

    def size_for(self, *args: Any) -> int:
        """The buffer's length for the unpack's arguments after the buffer (its ``dims``
        evaluated on them, as the unpack does)."""
        scope = dict(zip(self.args[1:], args, strict=True))
        return self.size(**{d: eval(expr, {}, scope) for d, expr in self.dims})  # noqa: S307

    def offset(self, name: str) -> int:
        """Where the field ``name`` (``a__b`` inside a nested layout) starts; its place
        must not depend on a dimension."""
        start = Dim()
        for local, size, _ in self.flat():
            if local == name:
                if start.coefs:
                    raise InvalidArgumentError(f"the offset of {name!r} depends on "
                                               f"{[n for n, _ in start.coefs]}")
                return start.const
            start = start + size
        raise InvalidArgumentError(f"no field {name!r} in the layout of "
                                   f"{self.state.__name__}; fields: "
                                   f"{[n for n, _, _ in self.flat()]}")

    def _construct(self, prefix: str, classes: dict[str, type]) -> str:
        """Source of the expression building ``state`` from the locals."""
        alias = f"_T{len(classes)}"
        classes[alias] = self.state
        held = dict(self.fields)
        parts = []
        for field in self.state._fields:
            size = held.get(field)
            if isinstance(size, Layout):
                parts.append(size._construct(f"{prefix}{field}__", classes))
            elif field in held:
                parts.append(prefix + field)
            elif field in self.args:
                parts.append(field)
            else:
                parts.append(f"{self.args[1]}.{field}")
        extra = set(held) - set(self.state._fields)
        if extra:
            raise InvalidArgumentError(f"{self.state.__name__} has no field(s) "
                                       f"{sorted(extra)}; fields: {list(self.state._fields)}")
        return f"{alias}({', '.join(parts)})"

    def source(self, name: str, returns_length: bool = True) -> tuple[str, dict[str, type]]:
        """The unpack's Python source and the classes it names."""
        classes: dict[str, type] = {}
        build = self._construct("", classes)
        buf = self.args[0]
        lines = [f"def {name}({', '.join(self.args)}):"]
        lines += [f"    dim_{d} = {expr}" for d, expr in self.dims]
        lines.append("    o = 0")
        for local, size, shape in self.flat():
            view = f"{buf}[o:o + {size.source()}]"
            lines.append(f"    {local} = {view}.reshape({_shape_source(shape)})" if shape else
                         f"    {local} = {view}")
            lines.append(f"    o = o + {size.source()}")
        lines.append(f"    return {build}, o" if returns_length else f"    return {build}")
        return "\n".join(lines) + "\n", classes

    def flag_reader(self, field: str, name: str, module: str) -> Any:
        """An ``@njit(cache=True, inline="always")`` ``name(buf) -> bool``: whether the (1,)
        field ``field`` is nonzero, read by its offset without building the views (a view
        costs its reference count on every tick)."""
        src = f"def {name}(buf):\n    return buf[{self.offset(field)}] != 0.0\n"
        fn = _compiled(src, name, module, {})
        fn.__doc__ = (f"Whether ``{self.state.__name__}.{field.replace('__', '.')}`` is "
                      "set, read without building the views.")
        return njit(cache=True, inline="always")(fn)

    def unpacker(self, name: str, module: str, returns_length: bool = True) -> Any:
        """The ``@njit(cache=True, inline="always")`` unpack, compiled as code of
        ``module``: returns (``state`` as named views of the buffer, the length), or the
        state alone when not ``returns_length``."""
        src, classes = self.source(name, returns_length)
        fn = _compiled(src, name, module, classes)
        LAYOUTS[f"{module}.{name}"] = (self, fn)
        fn.__doc__ = (f"(``{self.state.__name__}`` as named views of ``{self.args[0]}``"
                      + (", the layout's length)" if returns_length else ")")
                      + "; generated from its ``Layout`` (stage_layout.py).")
        return njit(cache=True, inline="always")(fn)


def _compiled(src: str, name: str, module: str, names: dict[str, Any]) -> Any:
    """The function ``name`` defined by ``src``, as code of ``module`` (its file and name:
    numba's cache and ``jit_cache``'s digest then treat it as that module's)."""
    namespace: dict[str, Any] = {"__name__": module, **names}
    exec(compile(src, sys.modules[module].__file__, "exec"), namespace)  # noqa: S102
    return namespace[name]
