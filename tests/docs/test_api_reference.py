"""The API reference (docs/api.md) documents every public name (``warpbem.__all__``) and every
options class of the package; the options' tables come from their declarations
(docs/_ext/options_table.py), so each declared field is in its class's table."""

import dataclasses
import importlib
import pkgutil
import re
import sys
from pathlib import Path

import warpbem
from warpbem.options import declared, reference_cells

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "docs" / "_ext"))
import options_table  # noqa: E402  (docs/_ext: the Sphinx extension under test)

DIRECTIVE = re.compile(r"^\.\. auto(module|class|function|exception)::[ \t]+(\S+)\n(?:[ \t]+:members:[ \t]*(.*))?", re.M)


def documented() -> list:
    """The objects the autodoc directives of docs/api.md name, with the members an automodule
    lists."""
    objects = []
    for kind, target, members in DIRECTIVE.findall((ROOT / "docs" / "api.md").read_text()):
        if kind == "module":
            module = importlib.import_module(target)
            objects += [module, *(getattr(module, name.strip()) for name in members.split(",") if name.strip())]
        else:
            module, _, name = target.rpartition(".")
            objects.append(getattr(importlib.import_module(module), name))
    return objects


def options_classes() -> set:
    """Every dataclass of the package with declared options."""
    found = set()
    for info in pkgutil.walk_packages(warpbem.__path__, "warpbem."):
        if info.name.endswith("__main__"):  # the command line: importing it runs it
            continue
        module = importlib.import_module(info.name)
        found |= {obj for obj in vars(module).values()
                  if options_table.options_class(obj) and obj.__module__.startswith("warpbem.")}
    return found


def test_every_public_name_is_documented():
    objects = documented()
    missing = [name for name in warpbem.__all__ if name != "__version__"
               and not any(getattr(warpbem, name) is obj for obj in objects)]
    assert not missing, f"docs/api.md has no autodoc entry for warpbem.{', warpbem.'.join(missing)}"


def test_every_options_class_is_documented_with_a_row_per_field():
    objects = documented()
    classes = options_classes()
    assert {"SolverOptions", "Flow", "TreecodeOptions", "StepPolicy", "Repulsion", "BondOptions",
            "DeformationOptions", "RunSettings"} <= {cls.__name__ for cls in classes}
    missing = [cls.__qualname__ for cls in classes if not any(cls is obj for obj in objects)]
    assert not missing, f"docs/api.md does not document the options classes {missing}"
    for cls in classes:
        rows = options_table.field_cells(cls)
        assert [row[0] for row in rows] == [f.name for f in dataclasses.fields(cls)]
        assert all(len(row) == 5 and all(row) for row in rows)
        declared_rows = [row for row in rows if row[0] in {name for name, _, _ in declared(cls)}]
        assert declared_rows == reference_cells(cls)  # the declarations' own text


def test_every_field_of_the_options_classes_is_declared():
    """A field without a declaration has no unit, range or meaning in the reference: only a
    field holding options of its own or filled in by the scene parser (a body's mesh) may."""
    undeclared = {f"{cls.__qualname__}.{field.name}" for cls in options_classes() for field in dataclasses.fields(cls)
                  if "option" not in field.metadata and not options_table.options_class(type(field.default))}
    assert undeclared <= {"BodySpec.mesh"}, f"not declared with warpbem.options.option: {sorted(undeclared)}"
