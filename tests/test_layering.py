"""The layers of the package (:mod:`fempipe.core.layers`) are kept: a static check.

Every ``fempipe/**.py`` is parsed with :mod:`ast`; nothing of fempipe is
imported (the layer table is read with :func:`runpy.run_path`, a file of data),
so the check is fast and cannot hide an import error.  Collected: every
``import`` and ``from ... import`` (relative ones resolved), also inside
functions and under ``if TYPE_CHECKING:``; the literal arguments of
``importlib.import_module``; and the module names in the registries of lazily
imported modules (:data:`REGISTRIES`: the CLI's ``SUBCOMMANDS``, the
benchmarks' ``BENCHMARK_MODULES``, the validation ``CASES``, the facade's
``_LAZY``).  The test fails, naming ``file:line`` and both layers, on

(a) an import of a higher layer;
(b) a private name (``_x``) of another fempipe module, imported
    (``from x import _y``) or read as an attribute (``module._y``);
(c) a cycle of module-level imports (the imports that run when a module is
    loaded: not those in functions or under ``TYPE_CHECKING``);
(d) a cycle of imports counting those inside functions, under ``TYPE_CHECKING``
    and in the registries (the lazy registries of the facade and the CLI,
    :data:`LAZY_REGISTRIES`, aside);
(e) more than :data:`MAX_FUNCTION_IMPORTS` imports inside functions outside
    ``fempipe/cli`` (one inside a function only defers a heavy dependency, with
    a comment saying so).  The target is 60; the cap is the count of the tree
    when (d) and (e) were written, two thirds of it the validation suite's.

The allow-lists below hold the violations of the tree when the test was
written, each with its fix; they and the cap only shrink.
"""

from __future__ import annotations

import ast
import runpy
from collections import Counter
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "fempipe"
_LAYERS = runpy.run_path(str(PACKAGE / "core" / "layers.py"))
layer_of = _LAYERS["layer_of"]

#: Assignments whose string values name modules imported later by name.
REGISTRIES = frozenset({"SUBCOMMANDS", "BENCHMARK_MODULES", "CASES", "_LAZY"})

#: (a) Imports of a higher layer: (importer, imported module).
ALLOWED_UPWARD: frozenset[tuple[str, str]] = frozenset()

#: (b) Private names of another module: (importer, defining module, name).
ALLOWED_PRIVATE: frozenset[tuple[str, str, str]] = frozenset()

#: (c) Cycles of module-level imports, each as the sorted tuple of its modules.
ALLOWED_CYCLES: frozenset[tuple[str, ...]] = frozenset()

#: Registries of modules loaded on first use whose cycles (d) allows: the facade's
#: public names and the CLI's subcommands (each module it names imports the registry's).
LAZY_REGISTRIES = frozenset({"_LAZY", "SUBCOMMANDS"})

#: (d) Cycles through imports inside functions, each as the sorted tuple of its modules.
ALLOWED_LAZY_CYCLES: frozenset[tuple[str, ...]] = frozenset()

#: (e) The most imports inside functions outside fempipe/cli.
MAX_FUNCTION_IMPORTS = 30


@dataclass(frozen=True)
class Import:
    """One import of ``target`` by ``module`` at ``path:line``.

    ``names`` are the names taken from it (``from target import a, b``);
    ``where`` is ``"module"`` for an import that runs when ``module`` is loaded,
    ``"function"`` inside a function, ``"type_checking"`` under ``if TYPE_CHECKING:``,
    or the name of the registry (:data:`REGISTRIES`) that names ``target``.
    """

    module: str
    path: str
    line: int
    target: str
    names: tuple[str, ...]
    where: str

    @property
    def eager(self) -> bool:
        """The import runs when ``module`` is loaded."""
        return self.where == "module"


@dataclass(frozen=True)
class PrivateUse:
    """``module`` (at ``path:line``) uses the private ``name`` of ``target``."""

    module: str
    path: str
    line: int
    target: str
    name: str


def module_name(path: Path, root: Path = ROOT) -> str:
    """``fempipe/a/b.py`` -> ``fempipe.a.b``; ``fempipe/a/__init__.py`` -> ``fempipe.a``."""
    parts = list(path.relative_to(root).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def package_sources(package: Path = PACKAGE) -> dict[str, tuple[str, str]]:
    """module name -> (path relative to the repository, source) of every ``.py`` file."""
    return {
        module_name(p, package.parent): (str(p.relative_to(package.parent)), p.read_text())
        for p in sorted(package.rglob("*.py"))
    }


def _is_private(name: str) -> bool:
    return name.startswith("_") and not name.startswith("__")


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _walk(node: ast.AST, where: str = "module") -> Iterator[tuple[ast.AST, str]]:
    """Every node below ``node`` with when it runs: ``"module"`` (when the module is
    loaded), ``"function"`` (in a function's body) or ``"type_checking"`` (never)."""
    for child in ast.iter_child_nodes(node):
        if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
            # decorators and defaults run at definition time, the body later
            for part in (*getattr(child, "decorator_list", ()), child.args):
                yield part, where
                yield from _walk(part, where)
            inner = where if where == "type_checking" else "function"
            for stmt in child.body if isinstance(child.body, list) else [child.body]:
                yield stmt, inner
                yield from _walk(stmt, inner)
        elif isinstance(child, ast.If) and _is_type_checking(child.test):
            for stmt in child.body:
                yield stmt, "type_checking"
                yield from _walk(stmt, "type_checking")
            for stmt in child.orelse:
                yield stmt, where
                yield from _walk(stmt, where)
        else:
            yield child, where
            yield from _walk(child, where)


def _resolve(module: str, is_package: bool, level: int, name: str | None) -> str:
    """The absolute module of ``from {'.' * level}{name} import ...`` inside ``module``."""
    if level == 0:
        return name or ""
    base = module.split(".")
    if not is_package:
        base = base[:-1]
    if level > 1:
        base = base[: len(base) - (level - 1)]
    return ".".join([*base, name] if name else base)


def _strings(node: ast.AST) -> Iterator[ast.Constant]:
    for sub in ast.walk(node):
        if isinstance(sub, ast.Constant) and isinstance(sub.value, str):
            yield sub


def scan(sources: Mapping[str, tuple[str, str]]) -> tuple[list[Import], list[PrivateUse]]:
    """The imports and the uses of private names of every module of ``sources``.

    ``sources`` maps a module name to (path, source), as :func:`package_sources`.
    """
    modules = set(sources)
    imports: list[Import] = []
    private: list[PrivateUse] = []
    for module, (path, source) in sources.items():
        tree = ast.parse(source, filename=path)
        is_package = path.endswith("__init__.py")
        package = module if is_package else module.rpartition(".")[0]
        aliases: dict[str, str] = {}  # local name -> fempipe module it is bound to

        def add(target: str, line: int, names: tuple[str, ...], where: str) -> None:
            imports.append(Import(module, path, line, target, names, where))  # noqa: B023

        def registry_module(text: str) -> str | None:
            for candidate in (text, f"{package}.{text}", f"fempipe.{text}"):  # noqa: B023
                if candidate in modules:
                    return candidate
            return None

        for node, where in _walk(tree):
            if isinstance(node, ast.Import):
                for a in node.names:
                    if a.name.split(".")[0] == "fempipe":
                        add(a.name, node.lineno, (), where)
                        if a.asname:
                            aliases[a.asname] = a.name
                        else:
                            aliases["fempipe"] = "fempipe"
            elif isinstance(node, ast.ImportFrom):
                base = _resolve(module, is_package, node.level, node.module)
                if base.split(".")[0] != "fempipe":
                    continue
                plain = []
                for a in node.names:
                    sub = f"{base}.{a.name}"
                    if sub in modules:  # from package import submodule
                        add(sub, node.lineno, (), where)
                        aliases[a.asname or a.name] = sub
                    else:
                        plain.append(a.name)
                        if _is_private(a.name) and base != module:
                            private.append(PrivateUse(module, path, node.lineno, base, a.name))
                if plain or not node.names:
                    add(base, node.lineno, tuple(plain), where)
            elif isinstance(node, ast.Call):
                func = node.func
                called = func.attr if isinstance(func, ast.Attribute) else getattr(func, "id", "")
                if called == "import_module" and node.args:
                    arg = node.args[0]
                    if isinstance(arg, ast.Constant) and isinstance(arg.value, str):
                        target = registry_module(arg.value)
                        if target:
                            add(target, node.lineno, (), where)
            elif isinstance(node, (ast.Assign, ast.AnnAssign)):
                targets = node.targets if isinstance(node, ast.Assign) else [node.target]
                names = {t.id for t in targets if isinstance(t, ast.Name)}
                if names & REGISTRIES and node.value is not None:
                    (registry,) = names & REGISTRIES
                    for const in _strings(node.value):
                        target = registry_module(const.value)
                        if target:
                            add(target, const.lineno, (), registry)
        for node in ast.walk(tree):
            if isinstance(node, ast.Attribute) and _is_private(node.attr):
                chain, value = [], node.value
                while isinstance(value, ast.Attribute):
                    chain.append(value.attr)
                    value = value.value
                if isinstance(value, ast.Name) and value.id in aliases:
                    target = ".".join([aliases[value.id], *reversed(chain)])
                    if target in modules and target != module:
                        private.append(PrivateUse(module, path, node.lineno, target, node.attr))
    return imports, private


def upward_imports(imports: list[Import]) -> list[str]:
    """Messages for (a): every import of a higher layer not in :data:`ALLOWED_UPWARD`."""
    out = []
    for imp in imports:
        mine, theirs = layer_of(imp.module), layer_of(imp.target)
        if mine is None or theirs is None:
            continue  # reported by test_every_module_has_a_layer
        if theirs[0] > mine[0] and (imp.module, imp.target) not in ALLOWED_UPWARD:
            what = f" ({', '.join(imp.names)})" if imp.names else ""
            out.append(
                f"{imp.path}:{imp.line}: {imp.module} (layer {mine[1]}) imports "
                f"{imp.target}{what} (layer {theirs[1]}, higher)"
            )
    return out


def private_uses(uses: list[PrivateUse]) -> list[str]:
    """Messages for (b): every private name of another module not in :data:`ALLOWED_PRIVATE`."""
    return [
        f"{u.path}:{u.line}: {u.module} (layer {_name(u.module)}) uses the private name "
        f"{u.name} of {u.target} (layer {_name(u.target)})"
        for u in uses
        if (u.module, u.target, u.name) not in ALLOWED_PRIVATE
    ]


def _name(module: str) -> str:
    layer = layer_of(module)
    return "none" if layer is None else layer[1]


def import_cycles(imports: list[Import]) -> list[str]:
    """Messages for (c): the cycles of module-level imports not in :data:`ALLOWED_CYCLES`."""
    return _cycles([i for i in imports if i.eager], ALLOWED_CYCLES, "module-level import")


def lazy_import_cycles(imports: list[Import]) -> list[str]:
    """Messages for (d): the cycles of imports, those inside functions, under
    ``TYPE_CHECKING`` and in the registries (but :data:`LAZY_REGISTRIES`) included, not in
    :data:`ALLOWED_LAZY_CYCLES`."""
    counted = [i for i in imports if i.where not in LAZY_REGISTRIES]
    return _cycles(counted, ALLOWED_LAZY_CYCLES, "import")


def strongly_connected(imports: list[Import]) -> list[list[str]]:
    """The cycles of the graph of ``imports``: its strongly connected components of more
    than one module, each sorted."""
    return [comp for comp, _ in _components(imports)]


def _components(imports: list[Import]) -> list[tuple[list[str], dict[str, dict[str, Import]]]]:
    graph: dict[str, dict[str, Import]] = {}
    for imp in imports:
        if imp.target != imp.module:
            graph.setdefault(imp.module, {}).setdefault(imp.target, imp)
    # Tarjan's strongly connected components
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    components: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph.get(v, {}):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                components.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return [(comp, graph) for comp in components]


def _cycles(imports: list[Import], allowed: frozenset, what: str) -> list[str]:
    out = []
    for comp, graph in _components(imports):
        if tuple(comp) in allowed:
            continue
        edges = [
            f"{imp.path}:{imp.line}: {imp.module} imports {imp.target} ({imp.where})"
            for v in comp
            for w, imp in graph.get(v, {}).items()
            if w in comp
        ]
        out.append(f"{what} cycle {' <-> '.join(comp)}: " + "; ".join(edges))
    return out


def function_imports(imports: list[Import]) -> list[Import]:
    """For (e): the imports inside functions outside fempipe/cli."""
    return [
        i
        for i in imports
        if i.where == "function" and layer_of(i.module) != layer_of("fempipe.cli")
    ]


@pytest.fixture(scope="module")
def scanned() -> tuple[list[Import], list[PrivateUse]]:
    return scan(package_sources())


def test_every_module_has_a_layer():
    """Each module of the package is in one layer of fempipe.core.layers.LAYERS."""
    missing = [m for m in package_sources() if layer_of(m) is None]
    assert not missing, f"modules in no layer (add their prefix to LAYERS): {missing}"


def test_no_import_of_a_higher_layer(scanned):
    problems = upward_imports(scanned[0])
    assert not problems, "\n".join(problems)


def test_no_private_name_of_another_module(scanned):
    problems = private_uses(scanned[1])
    assert not problems, "\n".join(problems)


def test_no_module_level_import_cycle(scanned):
    problems = import_cycles(scanned[0])
    assert not problems, "\n".join(problems)


def test_no_import_cycle_through_functions(scanned):
    """No modules import each other, not even inside functions (a lazy import that
    closes a cycle hides a dependency the layers should have settled)."""
    problems = lazy_import_cycles(scanned[0])
    assert not problems, "\n".join(problems)


def test_few_imports_inside_functions(scanned):
    """Imports inside functions outside fempipe/cli: at most :data:`MAX_FUNCTION_IMPORTS`
    (the target is 60; each defers a heavy dependency and says so)."""
    found = function_imports(scanned[0])
    by_package = Counter(".".join(i.module.split(".")[:2]) for i in found)
    assert len(found) <= MAX_FUNCTION_IMPORTS, (
        f"{len(found)} imports inside functions (at most {MAX_FUNCTION_IMPORTS}): "
        f"{dict(by_package.most_common())}"
    )


def test_the_allow_lists_hold_only_present_violations(scanned):
    """An entry whose violation is gone must be deleted (the lists only shrink)."""
    imports, uses = scanned
    upward = {(i.module, i.target) for i in imports}
    private = {(u.module, u.target, u.name) for u in uses}
    assert not ALLOWED_UPWARD - upward, sorted(ALLOWED_UPWARD - upward)
    assert not ALLOWED_PRIVATE - private, sorted(ALLOWED_PRIVATE - private)
    eager = {tuple(c) for c in strongly_connected([i for i in imports if i.eager])}
    assert not ALLOWED_CYCLES - eager, sorted(ALLOWED_CYCLES - eager)
    lazy = [i for i in imports if i.where not in LAZY_REGISTRIES]
    present = {tuple(c) for c in strongly_connected(lazy)}
    assert not ALLOWED_LAZY_CYCLES - present, sorted(ALLOWED_LAZY_CYCLES - present)


def test_the_registries_are_seen(scanned):
    """The lazily imported modules count as imports (the CLI's subcommands, the benchmarks,
    the validation cases, the facade's names)."""
    edges = {(i.module, i.target) for i in scanned[0]}
    assert ("fempipe.cli", "fempipe.cli.static") in edges
    assert ("fempipe.bench", "fempipe.bench.static") in edges
    assert ("fempipe.validation", "fempipe.validation.fig02a") in edges
    assert ("fempipe", "fempipe.model.params") in edges


SYNTHETIC = {
    # a lazy import of a higher layer, a private name, a relative import of the facade
    "fempipe.model.bad": (
        "fempipe/model/bad.py",
        "from fempipe.core.good import _hidden\n"
        "def f():\n"
        "    from fempipe.cli import main\n"
        "    from .. import Params\n",
    ),
    # a private name read as an attribute, under TYPE_CHECKING an upward import
    "fempipe.core.good": (
        "fempipe/core/good.py",
        "from typing import TYPE_CHECKING\n"
        "import fempipe.core.other as other\n"
        "x = other._secret\n"
        "if TYPE_CHECKING:\n"
        "    from fempipe.model import bad\n",
    ),
    # a module-level cycle core.other <-> core.third
    "fempipe.core.other": ("fempipe/core/other.py", "from . import third\n_secret = 1\n"),
    "fempipe.core.third": ("fempipe/core/third.py", "from fempipe.core.other import _secret\n"),
    # a cycle through an import inside a function: core.fourth <-> core.fifth
    "fempipe.core.fourth": ("fempipe/core/fourth.py", "def f():\n    from . import fifth\n"),
    "fempipe.core.fifth": ("fempipe/core/fifth.py", "import fempipe.core.fourth\n"),
    # the CLI's lazy registry: a cycle (d) allows; an import inside a function (e) ignores
    "fempipe.cli": (
        "fempipe/cli/__init__.py",
        'SUBCOMMANDS = {"sub": "fempipe.cli.sub"}\ndef main():\n    from fempipe.core import other\n',
    ),
    "fempipe.cli.sub": ("fempipe/cli/sub.py", "from fempipe.cli import main\n"),
    "fempipe": ("fempipe/__init__.py", ""),
    "fempipe.model": ("fempipe/model/__init__.py", ""),
    "fempipe.core": ("fempipe/core/__init__.py", ""),
}


def test_a_synthetic_bad_package_is_caught():
    """The check can fail: each kind of violation of a made-up package is reported,
    with file:line and both layers."""
    imports, uses = scan(SYNTHETIC)
    upward = upward_imports(imports)
    assert "fempipe/model/bad.py:3: fempipe.model.bad (layer model) imports fempipe.cli " in (
        "\n".join(upward)
    )
    assert any(m.startswith("fempipe/model/bad.py:4:") and "fempipe (Params)" in m for m in upward)
    assert any(m.startswith("fempipe/core/good.py:5:") and "layer model" in m for m in upward)
    private = private_uses(uses)
    assert any(m.startswith("fempipe/model/bad.py:1:") and "_hidden" in m for m in private)
    assert any(m.startswith("fempipe/core/good.py:3:") and "_secret" in m for m in private)
    assert any(m.startswith("fempipe/core/third.py:1:") and "_secret" in m for m in private)
    cycles = import_cycles(imports)
    assert len(cycles) == 1 and "fempipe.core.other <-> fempipe.core.third" in cycles[0]
    # the lazy and TYPE_CHECKING imports are no cycle (good -> other is eager, bad -> good lazy)
    assert "fempipe.model.bad" not in cycles[0]
    # (d): also the cycle through fourth's function and bad <-> good (under TYPE_CHECKING),
    # not the CLI's registry
    lazy = sorted(lazy_import_cycles(imports))
    assert [m.split(":")[0] for m in lazy] == [
        "import cycle fempipe.core.fifth <-> fempipe.core.fourth",
        "import cycle fempipe.core.good <-> fempipe.model.bad",
        "import cycle fempipe.core.other <-> fempipe.core.third",
    ]
    assert (
        "fempipe/core/fourth.py:2: fempipe.core.fourth imports fempipe.core.fifth (function)"
        in (lazy[0])
    )
    assert "fempipe.core.good imports fempipe.model.bad (type_checking)" in lazy[1]
    # (e): bad's two imports inside a function and fourth's; not the CLI's
    found = function_imports(imports)
    assert sorted((i.module, i.line) for i in found) == [
        ("fempipe.core.fourth", 2),
        ("fempipe.model.bad", 3),
        ("fempipe.model.bad", 4),
    ]
