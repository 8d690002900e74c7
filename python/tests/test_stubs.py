"""The type stubs declare what the module has: every public name and method, and nothing it lacks;
every public name has a docstring worth reading in help()."""

import ast
import inspect
import pathlib

import voxfuse
from voxfuse import _voxfuse

STUB = pathlib.Path(voxfuse.__file__).with_name("_voxfuse.pyi")


def stub_names():
    tree = ast.parse(STUB.read_text())
    top, members = set(), {}
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            top.add(node.name)
        if isinstance(node, ast.ClassDef):
            names = set()
            for item in node.body:
                if isinstance(item, ast.FunctionDef):
                    names.add(item.name)
                elif isinstance(item, ast.AnnAssign):
                    names.add(item.target.id)
            members[node.name] = names
    return top, members


def public(names):
    return {n for n in names if not n.startswith("_")}


def test_stubs_declare_the_module():
    top, members = stub_names()
    assert public(dir(_voxfuse)) == top
    assert set(voxfuse.__all__) == top
    for cls, declared in members.items():
        if issubclass(getattr(_voxfuse, cls), BaseException):
            continue
        assert public(dir(getattr(_voxfuse, cls))) == public(declared), cls


def test_public_names_are_documented():
    for name in voxfuse.__all__:
        obj = getattr(voxfuse, name)
        assert inspect.getdoc(obj), name
    for name in ("process", "process_frame", "render", "extract_mesh", "from_map", "summary"):
        assert len(inspect.getdoc(getattr(voxfuse.Pipeline, name))) > 40, name


def test_the_version_is_the_projects():
    # pyproject.toml and CMakeLists.txt agree (CMake checks it); the module reports the same.
    pyproject = pathlib.Path(__file__).resolve().parents[2] / "pyproject.toml"
    if not pyproject.exists():  # an installed copy of the tests
        assert voxfuse.__version__.count(".") == 2
        return
    line = next(l for l in pyproject.read_text().splitlines() if l.startswith("version = "))
    assert voxfuse.__version__ == line.split('"')[1]
