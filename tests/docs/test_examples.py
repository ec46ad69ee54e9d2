"""The worked examples of the public API run: every doctest (``>>>``) in the docstrings of the
names of ``warpbem.__all__`` (their modules' docstrings for ``mesh`` and ``units``, their
methods' too) gives the output it shows (``...`` matches anything), and every public class and
function, and both modules, has one. Exceptions and warnings need none (the examples show them
raised). The examples use the k = 2 sphere (24 elements), so all of them take seconds."""

import doctest
import inspect
import warnings

import pytest

import warpbem

PUBLIC = [name for name in warpbem.__all__ if name != "__version__"]
FLAGS = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE


def is_exception(obj) -> bool:
    return isinstance(obj, type) and issubclass(obj, BaseException)


def examples(name: str) -> list[doctest.DocTest]:
    """The doctests of ``warpbem.<name>``: of a module, those of its docstring and of what it
    defines; of a class, its docstring's and its methods'; of a function, its docstring's."""
    obj = getattr(warpbem, name)
    finder = doctest.DocTestFinder(exclude_empty=True)
    return [test for test in finder.find(obj, f"warpbem.{name}", module=inspect.getmodule(obj), globs={})
            if test.examples]


@pytest.mark.parametrize("name", [n for n in PUBLIC if not is_exception(getattr(warpbem, n))])
def test_every_public_class_function_and_module_has_a_worked_example(name):
    obj = getattr(warpbem, name)
    assert examples(name) and "Examples" in (obj.__doc__ or ""), \
        f"warpbem.{name}: its docstring has no Examples section with a >>> example"


@pytest.mark.parametrize("name", PUBLIC)
def test_the_examples_give_the_output_they_show(name, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # an example that writes files writes them here
    runner = doctest.DocTestRunner(optionflags=FLAGS)
    failed = []
    for test in examples(name):
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # an example must not warn unless it shows the warning
            result = runner.run(test, out=failed.append)
        assert result.failed == 0, f"{test.name}:\n{''.join(failed)}"
