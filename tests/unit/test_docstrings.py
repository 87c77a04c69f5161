"""numpydoc sections on the public API (`jointbench.__all__` and the classes it returns), in
the spirit of python-control's docstring test: every public callable has a docstring whose
Parameters section lists exactly its signature's parameters, in order; functions and methods
that return something have a Returns section; properties have a docstring.

numpydoc.docscrape parses the sections when it is installed; otherwise the sections are
parsed here (a header line underlined by dashes, `name : type` entries at the section's
indentation).
"""

from __future__ import annotations

import inspect
import re
import textwrap

import pytest

import jointbench

try:  # optional: the project does not depend on numpydoc
    from numpydoc.docscrape import NumpyDocString
except ImportError:  # pragma: no cover - depends on the environment
    NumpyDocString = None

PUBLIC = [name for name in jointbench.__all__ if name != "__version__"]


def _sections(doc: str) -> dict[str, list[str]]:
    """{section title: entry names} of a numpydoc docstring (Parameters, Returns, ...)."""
    if NumpyDocString is not None:
        parsed = NumpyDocString(doc)
        return {title: [p.name for p in parsed[title]] for title in
                ("Parameters", "Returns", "Raises", "Attributes") if parsed[title]} | \
            ({"Examples": []} if parsed["Examples"] else {})
    lines = textwrap.dedent(doc.split("\n", 1)[1] if "\n" in doc else "").splitlines()
    out: dict[str, list[str]] = {}
    title = None
    for i, line in enumerate(lines):
        if i + 1 < len(lines) and re.fullmatch(r"-{3,}", lines[i + 1].strip()) and line.strip():
            title = line.strip()
            out[title] = []
            continue
        if title is None or re.fullmatch(r"-{3,}", line.strip()) or not line.strip():
            continue
        if line == line.lstrip():   # an entry: `name : type`, `a, b : type` or `name`
            head = line.split(" : ")[0].strip()
            out[title] += [n.strip() for n in head.split(",")]
    return out


def _documented(obj) -> dict[str, list[str]]:
    doc = inspect.getdoc(obj)
    assert doc, f"{obj!r}: no docstring"
    return _sections(inspect.cleandoc(doc) if NumpyDocString else obj.__doc__)


def _signature_names(fn, skip_self: bool = False) -> list[str]:
    """The parameter names as numpydoc writes them: *args and **kwargs with their stars."""
    names = []
    for i, p in enumerate(inspect.signature(fn).parameters.values()):
        if skip_self and i == 0:
            continue
        names.append({p.VAR_POSITIONAL: "*", p.VAR_KEYWORD: "**"}.get(p.kind, "") + p.name)
    return names


def _returns_something(fn) -> bool:
    ret = inspect.signature(fn).return_annotation
    return ret not in (None, "None", inspect.Signature.empty)


def _check_callable(fn, label: str, skip_self: bool = False) -> None:
    sections = _documented(fn)
    names = _signature_names(fn, skip_self)
    if names:
        assert "Parameters" in sections, f"{label}: no Parameters section"
        assert sections["Parameters"] == names, (
            f"{label}: Parameters {sections['Parameters']} against the signature {names}")
    else:
        assert not sections.get("Parameters"), f"{label}: documents parameters it has not"
    if _returns_something(fn):
        assert sections.get("Returns"), f"{label}: no Returns section"


def _public_methods(cls):
    """(name, member) of the methods and properties a class defines itself."""
    for name, member in vars(cls).items():
        if name.startswith("_"):
            continue
        if isinstance(member, property) or inspect.isfunction(member):
            yield name, member


def _classes():
    return [name for name in PUBLIC if inspect.isclass(getattr(jointbench, name))]


def _functions():
    return [name for name in PUBLIC if not inspect.isclass(getattr(jointbench, name))]


def test_the_public_names_are_split_between_functions_and_classes():
    assert set(_functions()) >= {"simulate", "identify", "diagnose", "campaign", "survey",
                                 "import_log", "read_log", "write_log"}
    assert set(_classes()) >= {"Log", "Fit", "Estimate", "DiagnosisResult", "CampaignReport",
                               "SurveyResult", "ImportReport"}


@pytest.mark.parametrize("name", _functions())
def test_function_docstring_lists_its_parameters_and_returns(name):
    _check_callable(getattr(jointbench, name), f"jointbench.{name}")


@pytest.mark.parametrize("name", _classes())
def test_class_docstring_lists_its_fields(name):
    cls = getattr(jointbench, name)
    sections = _documented(cls)
    names = _signature_names(cls)
    assert sections.get("Parameters") == names, (
        f"{name}: Parameters {sections.get('Parameters')} against the signature {names}")


@pytest.mark.parametrize("name", _classes())
def test_methods_and_properties_are_documented(name):
    cls = getattr(jointbench, name)
    for attr, member in _public_methods(cls):
        label = f"jointbench.{name}.{attr}"
        if isinstance(member, property):
            assert inspect.getdoc(member.fget), f"{label}: property without a docstring"
        else:
            _check_callable(member, label, skip_self=True)


def test_the_parser_sees_a_missing_parameter():
    """The check can fail: a docstring that forgets a parameter is caught."""
    def f(a, b, **options) -> int:
        """Sum.

        Parameters
        ----------
        a : int
            One.
        **options
            More.

        Returns
        -------
        int
            The sum.
        """
    with pytest.raises(AssertionError, match="against the signature"):
        _check_callable(f, "f")
