"""Sphinx extension: every class of the API reference whose fields are declared options
(``warpbem.options.option``) gets the table of its fields under its description: unit,
default, allowed values and meaning, read from the declarations themselves (the ones the
checks, the scene parser and ``docs/scene-reference.md`` use), so the reference cannot drift
from the code.

The table goes in by ``autodoc-process-docstring`` as an ``options-table`` directive (before
the docstring's Examples), which builds the docutils table directly, so the meanings need no
escaping."""

from __future__ import annotations

import dataclasses
import importlib

from docutils import nodes
from sphinx.util.docutils import SphinxDirective

from warpbem.app.reference import TABLES
from warpbem.options import declared, reference_cells

HEADER = ("field", "unit", "default", "allowed", "meaning")
WIDTHS = (16, 6, 10, 14, 54)


def options_class(obj) -> bool:
    """Whether ``obj`` is a dataclass with declared options."""
    return isinstance(obj, type) and dataclasses.is_dataclass(obj) and bool(declared(obj))


def field_cells(cls) -> list[tuple[str, str, str, str, str]]:
    """Every field of ``cls`` in order: its declaration's cells; for a field holding options of
    their own (``SolverOptions.treecode``) a pointer to their table, for any other undeclared
    field (a mesh, filled in by the scene parser) its type, described in the class's text."""
    cells = {row[0]: row for row in reference_cells(cls)}
    rows = []
    for field in dataclasses.fields(cls):
        if field.name in cells:
            rows.append(cells[field.name])
        elif options_class(type(field.default)):
            name = type(field.default).__name__
            rows.append((field.name, "-", f"{name}()", f"a {name}", f"the `{name}` options (their own table)"))
        else:
            kind = field.type if isinstance(field.type, str) else getattr(field.type, "__name__", str(field.type))
            rows.append((field.name, "-", "-" if field.default in (None, dataclasses.MISSING) else repr(field.default),
                         kind, "see the description above"))
    return rows


def inline(text: str) -> list[nodes.Node]:
    """``text`` with its `backquoted` parts as code."""
    parts = text.split("`")
    return [nodes.literal(part, part) if i % 2 else nodes.Text(part) for i, part in enumerate(parts) if part]


def cell(text: str, code: bool = False) -> nodes.entry:
    paragraph = nodes.paragraph()
    paragraph += [nodes.literal(text, text)] if code else inline(text)
    return nodes.entry("", paragraph)


class OptionsTable(SphinxDirective):
    """``.. options-table:: module.Class``: the table of the class's declared options."""

    required_arguments = 1

    def run(self):
        module, _, name = self.arguments[0].rpartition(".")
        cls = getattr(importlib.import_module(module), name)
        table = nodes.table(classes=["options-table"])
        group = nodes.tgroup(cols=len(HEADER))
        table += group
        group += [nodes.colspec(colwidth=width) for width in WIDTHS]
        head = nodes.thead()
        head += nodes.row("", *[cell(title) for title in HEADER])
        body = nodes.tbody()
        for field, *rest in field_cells(cls):
            body += nodes.row("", cell(field, code=True), *[cell(text) for text in rest])
        group += [head, body]
        result = [table]
        sections = [section for section, classes, _ in TABLES if cls in classes]
        if sections:
            text = f"In a scene file: the `[{sections[0]}]` table (scene-file reference)."
            result.append(nodes.paragraph("", "", *inline(text)))
        return result


def add_table(app, what, name, obj, options, lines):
    """Put the options table of a documented options class before its docstring's Examples."""
    if what != "class" or not options_class(obj):
        return
    directive = ["", f".. options-table:: {obj.__module__}.{obj.__qualname__}", ""]
    examples = next((i for i, line in enumerate(lines) if line.strip() in (".. rubric:: Examples", "Examples")), None)
    at = len(lines) if examples is None else examples
    lines[at:at] = directive


def setup(app):
    app.add_directive("options-table", OptionsTable)
    app.connect("autodoc-process-docstring", add_table)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
