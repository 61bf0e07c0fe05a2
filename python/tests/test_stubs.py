"""The type stubs cover the compiled module, and every public name has a docstring."""

from __future__ import annotations

import ast
from pathlib import Path

import strata_sampling as ss
from strata_sampling import _strata

PKG = Path(ss.__file__).parent


def stub_names() -> dict[str, set[str]]:
    tree = ast.parse((PKG / "_strata.pyi").read_text())
    names: dict[str, set[str]] = {}
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            members = set()
            for item in node.body:
                if isinstance(item, ast.FunctionDef):
                    members.add(item.name)
                elif isinstance(item, ast.AnnAssign) and isinstance(item.target, ast.Name):
                    members.add(item.target.id)
            names[node.name] = members
        elif isinstance(node, ast.FunctionDef):
            names[node.name] = set()
    return names


def test_stubs_cover_the_compiled_module():
    stubs = stub_names()
    public = {n for n in dir(_strata) if not n.startswith("_")}
    assert public == set(stubs), public ^ set(stubs)
    for cls in ("Field", "Sampler", "Samples"):
        members = {n for n in dir(getattr(_strata, cls)) if not n.startswith("_")}
        assert members == stubs[cls] - {"__init__", "__len__"}, (cls, members ^ stubs[cls])
    assert (PKG / "py.typed").exists()


def test_every_public_name_has_a_docstring():
    for name in ss.__all__:
        obj = getattr(ss, name)
        assert obj.__doc__ and obj.__doc__.strip(), name
    for cls in (ss.Sampler, ss.Samples, ss.Field):
        for name in dir(cls):
            if not name.startswith("_"):
                assert getattr(cls, name).__doc__, (cls.__name__, name)
