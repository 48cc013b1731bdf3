"""Every docstring example of the package runs (the extension's classes, methods and
functions, and the Python modules): documentation that cannot go stale."""

import doctest
import inspect

import coagula
import coagula._coagula as ext
import coagula.exact


def docstrings():
    seen = []
    for mod in (coagula, coagula.exact, ext):
        seen.append((mod.__name__, mod))
        for name, obj in vars(mod).items():
            if name.startswith("__") or not (inspect.isclass(obj) or callable(obj)):
                continue
            seen.append((f"{mod.__name__}.{name}", obj))
            if inspect.isclass(obj):
                for m, f in vars(obj).items():
                    if not m.startswith("__") and getattr(f, "__doc__", None):
                        seen.append((f"{mod.__name__}.{name}.{m}", f))
    return seen


def test_every_docstring_example_runs():
    finder = doctest.DocTestFinder(recurse=False)
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    examples = 0
    for name, obj in docstrings():
        doc = getattr(obj, "__doc__", None)
        if not doc or ">>>" not in doc:
            continue
        test = doctest.DocTestParser().get_doctest(doc, {"coagula": coagula}, name, None, 0)
        examples += len(test.examples)
        runner.run(test)
    del finder
    assert runner.failures == 0, f"{runner.failures} docstring examples failed"
    # the classes and the entry points carry examples
    assert examples >= 15, examples


def test_the_public_api_is_documented():
    for name in coagula.__all__:
        obj = getattr(coagula, name)
        assert obj.__doc__ and len(obj.__doc__) > 20, name


def test_the_readme_python_example_runs():
    """The README's "From Python" example, as written there."""
    import os
    import re

    readme = os.path.join(os.path.dirname(__file__), "..", "..", "README.md")
    with open(readme, encoding="utf-8") as f:
        blocks = re.findall(r"```python\n(.*?)```", f.read(), flags=re.S)
    assert blocks, "README has no Python example"
    scope = {}
    exec(compile(blocks[0], "README.md", "exec"), scope)
    sim, ds = scope["sim"], scope["ds"]
    assert sim.time == 2.0 and abs(sim.moment(0) - 0.1353) < 0.01
    assert "mean" in ds
