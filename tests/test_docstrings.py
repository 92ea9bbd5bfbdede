"""The ROS-free public API documents itself: every public function, method and class has a numpydoc docstring
whose Parameters section names exactly the arguments the signature takes.

The shape of the check is python-control's control/tests/docstrings_test.py: walk each module's public names,
read the signature with inspect, and compare it with the names the docstring's Parameters (or Other Parameters)
section lists. A class's arguments are its ``__init__``'s, documented in the class docstring (numpydoc's place for
them) or in ``__init__``'s own; a dataclass may list its fields under Attributes instead. One test per package, so
a failure says which package's docstrings need work.
"""
import dataclasses
import importlib
import inspect
import pkgutil
import re
from types import ModuleType
from typing import Callable, Iterator

import pytest

#: the package that holds the trajectory type, time scaling, Riccati gains, measures and plan errors; change this
#: one name when those modules move to their own package
CONTROL_CORE_PACKAGE = "swim_control"
CONTROL_CORE_MODULES = tuple(f"{CONTROL_CORE_PACKAGE}.{name}"
                             for name in ("trajectory", "time_scaling", "riccati", "measures", "errors"))

#: the ROS-free public API, per package: every module of swim_model (``None``: walk the package), the control core,
#: and the planner's and tracker's algorithm modules (their nodes and CLIs are outside this check)
PUBLIC_API = {
    "swim_model": None,
    "swim_control": CONTROL_CORE_MODULES,
    "swim_planner": ("swim_planner.maneuver", "swim_planner.primitive_solver", "swim_planner.library"),
    "swim_controller": ("swim_controller.tracker",),
}

#: numpydoc's section headings whose entries are argument names
ARGUMENT_SECTIONS = ("Parameters", "Other Parameters")
#: where a dataclass may list its fields (the arguments of its generated ``__init__``)
FIELD_SECTIONS = ARGUMENT_SECTIONS + ("Attributes",)
#: a numpydoc section heading: a title line underlined by dashes of the same length
SECTION_UNDERLINE = re.compile(r"^-{3,}\s*$")


def module_names(package: str) -> tuple[str, ...]:
    """The public modules the check covers in one package of PUBLIC_API."""
    listed = PUBLIC_API[package]
    if listed is not None:
        return listed
    root = importlib.import_module(package)
    walked = [info.name for info in pkgutil.walk_packages(root.__path__, prefix=f"{package}.")
              if not any(part.startswith("_") or part in ("testing", "test") for part in info.name.split("."))]
    return (*walked, package)  # each object reported where it is defined, before the package re-exports it


def numpydoc_sections(docstring: str) -> dict[str, list[str]]:
    """Split a cleaned docstring (inspect.getdoc) into its numpydoc sections: {heading: lines under it}."""
    lines = docstring.splitlines()
    sections: dict[str, list[str]] = {}
    current = "Summary"
    sections[current] = []
    index = 0
    while index < len(lines):
        line = lines[index]
        underline = lines[index + 1] if index + 1 < len(lines) else ""
        if line.strip() and SECTION_UNDERLINE.match(underline) and len(underline.strip()) == len(line.strip()):
            current = line.strip()
            sections.setdefault(current, [])
            index += 2
            continue
        sections[current].append(line)
        index += 1
    return sections


def documented_names(docstring: str, headings: tuple[str, ...]) -> list[str]:
    """The names a numpydoc docstring's sections list: each unindented ``name : type`` (or ``a, b : type``, or a
    bare ``name``) line; ``*args`` and ``**kwargs`` keep their stars."""
    sections = numpydoc_sections(docstring)
    names = []
    for heading in headings:
        for line in sections.get(heading, []):
            if not line.strip() or line[0].isspace():
                continue
            names.extend(name.strip() for name in line.split(" : ")[0].rstrip(":").split(","))
    return names


def argument_names(function: Callable) -> list[str]:
    """The arguments a caller passes, as a numpydoc Parameters section names them (``*args``, ``**kwargs``)."""
    names = []
    for index, parameter in enumerate(inspect.signature(function).parameters.values()):
        if index == 0 and parameter.name in ("self", "cls") or parameter.name.startswith("_"):
            continue
        stars = {inspect.Parameter.VAR_POSITIONAL: "*", inspect.Parameter.VAR_KEYWORD: "**"}.get(parameter.kind, "")
        names.append(stars + parameter.name)
    return names


def argument_problems(where: str, arguments: list[str], docstring: str, headings: tuple[str, ...]) -> list[str]:
    """Each argument the docstring leaves out, and each name it documents that is no argument."""
    documented = documented_names(docstring, headings)
    missing = [name for name in arguments if name not in documented]
    extra = [name for name in documented if name not in arguments]
    return ([f"{where}: argument '{name}' not documented" for name in missing]
            + [f"{where}: documents '{name}', which is no argument" for name in extra])


def function_problems(where: str, function: Callable) -> list[str]:
    """What a public function's or method's docstring leaves out or gets wrong."""
    docstring = inspect.getdoc(function)
    if not docstring:
        return [f"{where}: no docstring"]
    return argument_problems(where, argument_names(function), docstring, ARGUMENT_SECTIONS)


def class_problems(where: str, cls: type) -> list[str]:
    """A public class's docstring and its ``__init__`` arguments, then each public method's docstring."""
    docstring = inspect.getdoc(cls) if cls.__doc__ else None
    if not docstring:
        return [f"{where}: no docstring"]
    problems = []
    init = cls.__dict__.get("__init__")
    # a Protocol's __init__ is typing's placeholder (*args, **kwargs), not an interface of the class
    if inspect.isfunction(init) and not getattr(cls, "_is_protocol", False):
        init_docstring = init.__doc__ and inspect.getdoc(init) or ""
        headings = FIELD_SECTIONS if dataclasses.is_dataclass(cls) else ARGUMENT_SECTIONS
        problems += argument_problems(where, argument_names(init), docstring + "\n" + init_docstring, headings)
    for name, member in vars(cls).items():
        if name.startswith("_"):
            continue
        if isinstance(member, (staticmethod, classmethod)):
            member = member.__func__
        if isinstance(member, property):
            if not member.__doc__:
                problems.append(f"{where}.{name}: no docstring")
        elif inspect.isfunction(member):
            problems += function_problems(f"{where}.{name}", member)
    return problems


def public_objects(module: ModuleType) -> Iterator[tuple[str, object]]:
    """The public functions and classes a module defines (its ``__all__`` when it has one)."""
    names = getattr(module, "__all__", None)
    for name in names if names is not None else sorted(vars(module)):
        obj = getattr(module, name)
        if name.startswith("_") or not (inspect.isfunction(obj) or inspect.isclass(obj)):
            continue
        if names is None and getattr(obj, "__module__", None) != module.__name__:
            continue  # imported from elsewhere: checked where it is defined
        yield name, obj


def module_problems(module: ModuleType, checked: set[int]) -> list[str]:
    """Everything wrong with one module's public API's docstrings; ``checked`` holds the ids of the objects
    already checked (a package's ``__init__`` re-exports its modules' names), and gains this module's."""
    problems = []
    for name, obj in public_objects(module):
        if id(obj) in checked:
            continue
        checked.add(id(obj))
        where = f"{module.__name__}.{name}"
        problems += class_problems(where, obj) if inspect.isclass(obj) else function_problems(where, obj)
    return problems


@pytest.mark.parametrize("package", sorted(PUBLIC_API))
def test_public_api_is_documented(package):
    problems: list[str] = []
    checked: set[int] = set()
    for name in module_names(package):
        problems += module_problems(importlib.import_module(name), checked)
    assert not problems, f"{package}: {len(problems)} docstring problems:\n" + "\n".join(problems)


def test_the_check_finds_what_it_is_for():
    """The checker itself: a missing argument, a stale one, a missing docstring, and a correct numpydoc
    docstring that passes."""
    def documented(rate_hz: float, *samples: float, window: int = 3, **options: str) -> float:
        """Average.

        Parameters
        ----------
        rate_hz : float
            Sample rate, Hz.
        *samples : float
            The samples.
        window, **options
            Window length and options.

        Returns
        -------
        float
            The mean.
        """
        return rate_hz

    def stale(rate_hz: float) -> float:
        """Average.

        Parameters
        ----------
        period_s : float
            Sample period, s.
        """
        return rate_hz

    def bare(rate_hz: float) -> float:
        return rate_hz

    assert function_problems("documented", documented) == []
    assert function_problems("stale", stale) == ["stale: argument 'rate_hz' not documented",
                                                 "stale: documents 'period_s', which is no argument"]
    assert function_problems("bare", bare) == ["bare: no docstring"]

    @dataclasses.dataclass
    class Record:
        """A record.

        Attributes
        ----------
        mass_kg : float
            Mass, kg.
        """

        mass_kg: float
        length_m: float

    assert class_problems("Record", Record) == ["Record: argument 'length_m' not documented"]


#: the packages of nodes and tools: their __init__ exports the public names of their ROS-free modules
NODE_PACKAGES = ("swim_bringup", "swim_hw_bridge", "swim_ros", "swim_sim", "swim_viz")


@pytest.mark.parametrize("package", sorted(PUBLIC_API) + list(NODE_PACKAGES))
def test_package_exports_its_api(package):
    """Each package's ``__init__`` lists its public API in ``__all__``, and every name listed is there."""
    module = importlib.import_module(CONTROL_CORE_PACKAGE if package == "swim_control" else package)
    exported = getattr(module, "__all__", None)
    assert exported, f"{module.__name__}.__init__ has no __all__"
    assert [name for name in exported if not hasattr(module, name)] == []
