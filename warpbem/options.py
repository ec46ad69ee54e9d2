"""Options declared once: each setting is a field of a frozen dataclass whose metadata holds
its unit, allowed range (or choices) and one line of doc (``option``). From that one
declaration come

* the checks when the dataclass is made (``validate``, called from ``__post_init__``), with
  messages that name the field and the allowed range;
* the scene parser's reading of a TOML table (``from_table``), whose messages name the field by
  its dotted scene key (``flow.viscosity``);
* the scene-file reference (``reference_rows``, ``warpbem.app.reference``).

An option may also declare the ``plausible`` magnitudes of its values (``warpbem.units``): a
value outside them was most likely typed in another unit (a position of 6, meaning 6 um, is 6 m).
They are checked while a scene file is read (``plausible_magnitudes``, on unless the scene says
``any_scale = true``), not by the API, which takes any consistent units (Stokes flow has no scale
of its own: the verification tests use unit spheres) and whose solvers rebuild their settings
from numbers already accepted.

A default that depends on the context (``None`` resolved elsewhere, e.g. the GMRES tolerance by
the precision) says so in its doc and is resolved in one named place.
"""

from __future__ import annotations

import contextlib
import contextvars
import dataclasses
import math
from dataclasses import dataclass

from . import units


class OptionError(ValueError):
    """A value outside what its option allows; the message names the option."""


@dataclass(frozen=True)
class Spec:
    """What an option allows: ``kind`` (float, int, bool or str; with ``length`` > 0 a list of
    that many), a range [low, high] (``low_open``/``high_open``: excluded; of each item of a
    list), ``choices`` for strings (none: any string), ``optional``: None allowed (its meaning
    in ``doc``); ``unit`` (SI) and ``doc`` for the reference; ``plausible``: the (low, high)
    magnitudes a value of a scene file may take (module docstring; none: any)."""

    kind: object
    doc: str
    unit: str = "1"
    low: float = -math.inf
    high: float = math.inf
    low_open: bool = False
    high_open: bool = False
    choices: tuple = ()
    optional: bool = False
    length: int = 0
    plausible: tuple = ()

    def range_text(self) -> str:
        if self.choices:
            return ", ".join(repr(c) for c in self.choices)
        items = f"{self.length} {'integers' if self.kind is int else 'numbers'}" if self.length else ""
        if self.kind in (bool, str) or (self.low == -math.inf and self.high == math.inf):
            return items
        closed = (not self.low_open and self.low > -math.inf, not self.high_open and self.high < math.inf)
        bounds = f"{'[' if closed[0] else '('}{self.low:g}, {self.high:g}{']' if closed[1] else ')'}"
        return f"{items}, each in {bounds}" if items else bounds

    def plausible_text(self) -> str:
        """The plausible magnitudes, for the references: "scene files: plausible 1e-08 to 0.001",
        "scene files: each of plausible magnitude <= 0.01" (the API does not check them)."""
        if not self.plausible:
            return ""
        low, high = self.plausible
        text = f"plausible {low:g} to {high:g}" if low > 0 else f"plausible magnitude <= {high:g}"
        return f"scene files: {'each of ' if self.length else ''}{text}"


def option(default, doc: str, unit: str = "1", *, kind=None, low=-math.inf, high=math.inf, low_open=False,
           high_open=False, choices=(), optional=None, length=0, plausible=()):
    """A dataclass field declared with its ``Spec`` (kind from the default unless given)."""
    kind = kind or type(default)
    optional = default is None if optional is None else optional
    spec = Spec(kind, doc, unit, low, high, low_open, high_open, tuple(choices), optional, length, tuple(plausible))
    return dataclasses.field(default=default, metadata={"option": spec})


def declared(cls) -> list[tuple[str, object, Spec]]:
    """(name, default, Spec) of each declared option of a dataclass, in field order."""
    return [(f.name, f.default, f.metadata["option"]) for f in dataclasses.fields(cls) if "option" in f.metadata]


def check(where: str, spec: Spec, value):
    """``value`` checked against ``spec`` (and converted: ints stay ints, vectors become tuples);
    OptionError naming ``where`` otherwise."""
    if value is None and spec.optional:
        return None
    if spec.kind is bool:
        if not isinstance(value, bool):
            raise OptionError(f"{where}: expected true or false, got {value!r}")
        return value
    if spec.length:
        if not isinstance(value, (list, tuple)) or len(value) != spec.length:
            items = "integers" if spec.kind is int else "numbers"
            raise OptionError(f"{where}: expected a list of {spec.length} {items}, got {value!r}")
        item = dataclasses.replace(spec, length=0, optional=False)
        return tuple(check(f"{where}[{i}]", item, v) for i, v in enumerate(value))
    if spec.kind is str:
        if not isinstance(value, str) or (spec.choices and value not in spec.choices):
            raise OptionError(f"{where}: {value!r} is not one of {spec.range_text()}" if spec.choices
                              else f"{where}: expected a string, got {value!r}")
        return value
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise OptionError(f"{where}: expected a finite number, got {value!r}")
    if spec.kind is int and int(value) != value:
        raise OptionError(f"{where}: expected an integer, got {value!r}")
    if (value < spec.low or value > spec.high or (spec.low_open and value == spec.low)
            or (spec.high_open and value == spec.high)):
        hint = units.hint(spec.unit, value) if value > spec.high else ""
        raise OptionError(f"{where}: {value:g} is outside the allowed range {spec.range_text()}"
                          + (f"; {hint}" if hint else ""))
    if spec.plausible:
        check_plausible(where, value, spec.unit, spec.plausible)
    return int(value) if spec.kind is int else float(value)


_PLAUSIBLE_CHECKED = contextvars.ContextVar("plausible_checked", default=False)


@contextlib.contextmanager
def plausible_magnitudes(checked: bool = True):
    """Within it, values are checked against their options' plausible magnitudes (a scene file
    being read, unless it says ``any_scale = true``; module docstring)."""
    token = _PLAUSIBLE_CHECKED.set(checked)
    try:
        yield
    finally:
        _PLAUSIBLE_CHECKED.reset(token)


def check_plausible(where: str, value: float, unit: str, plausible: tuple, what: str = "") -> None:
    """OptionError naming ``where`` if ``value`` (in ``unit``; ``what``: its description in the
    message) lies outside the ``plausible`` (low, high) magnitudes while they are checked, with
    the unit it was likely typed in."""
    low, high = plausible
    if not _PLAUSIBLE_CHECKED.get() or low <= abs(value) <= high:
        return
    over = abs(value) > high
    hint = units.hint(unit, value) if over else ""
    raise OptionError(f"{where}: {what}{value:g} {unit} is {'over' if over else 'under'} the plausible"
                      f" {'magnitude ' if value < 0 else ''}{high if over else low:g} {unit}"
                      + (f"; {hint}" if hint else "") + "; a scene meaning it says any_scale = true")


def validate(instance, where: str = "") -> None:
    """Check (and convert in place) every declared option of a frozen dataclass instance; call
    from ``__post_init__``. ``where``: the prefix of the names in the messages."""
    for name, _, spec in declared(type(instance)):
        value = check(f"{where}{name}", spec, getattr(instance, name))
        object.__setattr__(instance, name, value)


def check_keys(where: str, table, allowed, required=()) -> dict:
    """``table`` is a table (dict) with only ``allowed`` keys and every ``required`` one."""
    if not isinstance(table, dict):
        raise OptionError(f"{where}: expected a table, got {table!r}")
    unknown = sorted(set(table) - set(allowed))
    if unknown:
        raise OptionError(f"{where}: unknown key {unknown[0]!r}; allowed keys: {', '.join(sorted(allowed))}")
    missing = [k for k in required if k not in table]
    if missing:
        raise OptionError(f"{where}: missing required key {missing[0]!r}")
    return table


def from_table(cls, table: dict, where: str, required=(), **given):
    """An instance of ``cls`` from a scene table: each key a declared option, checked with its
    dotted name ``where.key``; keys absent take their declared default; ``required``: keys that
    must be given; ``given``: fields set by the caller (not scene keys). Unknown keys are
    refused with the allowed ones listed."""
    names = {name: spec for name, _, spec in declared(cls)}
    check_keys(where, table, names, required)
    values = {key: check(f"{where}.{key}", names[key], value) for key, value in table.items()}
    try:
        return cls(**values, **given)
    except OptionError as err:  # a check across fields: name it by the scene's prefix
        raise OptionError(f"{where}.{err}") from err


def reference_cells(cls) -> list[tuple[str, str, str, str, str]]:
    """(name, unit, default, allowed, meaning) of each of ``cls``'s options, as text; a default
    of ``-`` is resolved from the context (its meaning says how), allowed ``-``: any value."""
    cells = []
    for name, default, spec in declared(cls):
        shown = "-" if default is None else (str(default).lower() if isinstance(default, bool) else
                                             repr(list(default)) if isinstance(default, tuple) else repr(default))
        allowed = "; ".join(text for text in (spec.range_text(), spec.plausible_text()) if text) or "-"
        cells.append((name, spec.unit, shown, allowed, spec.doc))
    return cells


def reference_rows(cls, section: str) -> list[str]:
    """Markdown table rows ``| key | unit | default | allowed | meaning |`` of ``cls``'s options."""
    return [f"| `{section}.{name}` | {unit} | {shown} | {allowed} | {doc} |"
            for name, unit, shown, allowed, doc in reference_cells(cls)]
