"""Every public function and method documents all of its parameters (numpydoc style)."""

import importlib
import inspect
import pkgutil
import re

import pytest

import wheelbase

SKIP_MODULES = {"wheelbase.cli", "wheelbase._validate"}


def public_modules():
    for info in pkgutil.walk_packages(wheelbase.__path__, "wheelbase."):
        name = info.name
        if name in SKIP_MODULES or any(part.startswith("_") for part in name.split(".")[1:]):
            continue
        if name.startswith("wheelbase.commands") or name.endswith("make_maps"):
            continue
        yield importlib.import_module(name)


def documented_callables():
    seen = set()
    for module in public_modules():
        for name in getattr(module, "__all__", []):
            obj = getattr(module, name)
            targets = [obj]
            if inspect.isclass(obj):
                targets = [
                    member
                    for member_name, member in vars(obj).items()
                    if not member_name.startswith("_") and inspect.isfunction(member)
                ]
            for target in targets:
                if inspect.isfunction(target) and id(target) not in seen:
                    seen.add(id(target))
                    yield f"{module.__name__}.{target.__qualname__}", target


def parameters_needing_docs(function):
    names = []
    for parameter in inspect.signature(function).parameters.values():
        if parameter.name in {"self", "cls"} or parameter.kind in (
            parameter.VAR_POSITIONAL,
            parameter.VAR_KEYWORD,
        ):
            continue
        names.append(parameter.name)
    return names


CASES = sorted(documented_callables())


@pytest.mark.parametrize(("qualname", "function"), CASES, ids=[c[0] for c in CASES])
def test_public_callable_documents_its_parameters(qualname, function):
    doc = inspect.getdoc(function) or ""
    assert doc.strip(), f"{qualname} has no docstring"
    names = parameters_needing_docs(function)
    # One parameter may be described in prose; two or more need a numpydoc Parameters section.
    if len(names) <= 1:
        return
    assert "Parameters\n----------" in doc, f"{qualname} needs a Parameters section for {names}"
    section = doc.split("Parameters\n----------", 1)[1]
    section = re.split(r"\n(Returns|Raises|Yields|Notes|Examples|See Also)\n-{3,}", section)[0]
    listed = set()
    for match in re.finditer(r"^([\w, ]+?)\s*:", section, re.M):
        listed.update(part.strip() for part in match.group(1).split(","))
    missing = [name for name in names if name not in listed]
    assert not missing, f"{qualname} does not document {missing}"
