"""The package is layered: no import cycle, no import from a lower layer to a higher one, and no
function-level import except of an optional dependency (each commented ``# optional: <why>``).

The graph is read from the source with :mod:`ast` (nothing is imported): every ``import`` and
``from ... import`` of a module, at module level or inside a function, relative imports resolved, and a
name taken from a package (``from imunav.ins import ZuptFilter``) followed through the package's
``__init__`` re-exports to the module that defines it.  Imports under ``if TYPE_CHECKING:`` are
annotations only (they never run) and are not edges.  Importing ``a.b.c`` also runs ``a/__init__`` and
``a/b/__init__`` (unless they are the importer's own packages, already running): those are edges too,
since a package ``__init__`` that re-exports its submodules imports them all (importing
``imunav.io.csv`` runs ``imunav/io/__init__``, which imports every format).

The layers are those of ``docs/design.md`` section 1 (:data:`LAYERS`).  Beyond them: the command line
(``imunav.cli``) imports only public library modules and names (no ``_private`` module or name outside
``cli`` itself), nothing outside ``cli`` imports it, and nothing below the orchestration package ``imunav.lab``
imports that.
"""

from __future__ import annotations

import ast
import os
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src"

#: Low -> high.  A module belongs to the layer of the longest prefix listed; a module may import from
#: its own layer or a lower one.  Keep in step with the table of docs/design.md section 1.
LAYERS: list[tuple[str, tuple[str, ...]]] = [
    ("core", ("imunav", "imunav.errors", "imunav.units", "imunav.rotation", "imunav._rotation_kernels", "imunav.atmosphere",
              "imunav.earth", "imunav.allan_models", "imunav.crossval", "imunav._timeseries_kernels",
              "imunav.provenance", "imunav.files", "imunav.lab.runfolder", "imunav.toml", "imunav.filters._common",
              "imunav.filters._kernels", "imunav.filters._core", "imunav.results", "imunav._quantiles",
              "imunav.vocabulary")),
    ("recordings, io", ("imunav.timeseries", "imunav.io")),
    ("noise, calib, filters", ("imunav.noise", "imunav.calib", "imunav.filters")),
    ("sim, attitude, ins, airdata, learn", ("imunav.sim", "imunav.attitude", "imunav.ins", "imunav.airdata",
                                            "imunav.learn", "imunav.scenarios")),
    ("lab: runner, config, steps, batch, montecarlo, runfolder, report; notebook", ("imunav.lab", "imunav.notebook")),
    ("cli", ("imunav.cli",)),
]

#: The one function-level import of the package itself: the package root's lazy re-export (PEP 562 ``__getattr__``)
#: of the notebook entry points (``imunav.read`` ...), so that ``import imunav`` gives them without loading the
#: estimators (docs/design.md, section 1).  Not an edge of the graph: it runs only when a user asks for one.
LAZY_REEXPORTS = frozenset({("imunav", "imunav.notebook"),
                            # imunav.io's readers and writers (issue 35): importing one reader (imunav.io.ulog) loads
                            # neither pandas nor scipy.io; the names resolve through the __init__'s TYPE_CHECKING block
                            ("imunav.io", "imunav.io.core"), ("imunav.io", "imunav.io.dataframe")})

#: Top-level packages that may be imported inside a function: optional extras, or matplotlib, which
#: only drawing needs (``import imunav`` and ``imunav --help`` must not load it).
OPTIONAL_IMPORTS = frozenset({"torch", "dask", "distributed", "matplotlib", "rosbags", "pyulog", "pyarrow", "yaml",
                              "h5py", "pywt"})  # the hdf5 and wavelet extras


@dataclass(frozen=True)
class Import:
    """One import statement's edge: ``source`` imports ``target`` (a module of the package)."""

    source: str
    target: str
    line: int
    in_function: bool


@dataclass
class Graph:
    """Modules of a package and the imports between them (plus function-level imports of other packages)."""

    modules: dict[str, Path]
    edges: list[Import] = field(default_factory=list)
    #: (module, line, top-level package, commented) of every function-level import outside the package
    external_in_function: list[tuple[str, int, str, bool]] = field(default_factory=list)


def _module_name(path: Path, src: Path) -> str:
    parts = list(path.relative_to(src).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _is_type_checking(node: ast.If) -> bool:
    t = node.test
    return (isinstance(t, ast.Name) and t.id == "TYPE_CHECKING") or (
        isinstance(t, ast.Attribute) and t.attr == "TYPE_CHECKING")


def _imports(tree: ast.AST):
    """(node, in_function) for every import that runs (those under ``if TYPE_CHECKING:`` do not)."""
    stack: list[tuple[ast.AST, bool]] = [(tree, False)]
    while stack:
        node, in_fn = stack.pop()
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.If) and _is_type_checking(child):
                stack.extend((c, in_fn) for c in child.orelse)
                continue
            if isinstance(child, (ast.Import, ast.ImportFrom)):
                yield child, in_fn
            stack.append((child, in_fn or isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda))))


def build_graph(src: Path, package: str) -> Graph:
    """The import graph of ``src/<package>`` (see the module docstring)."""
    modules = {_module_name(p, src): p for p in sorted((src / package).rglob("*.py"))}
    packages = {m for m, p in modules.items() if p.name == "__init__.py"}
    trees = {m: ast.parse(p.read_text(encoding="utf-8"), str(p)) for m, p in modules.items()}
    lines = {m: p.read_text(encoding="utf-8").splitlines() for m, p in modules.items()}

    def absolute(m: str, node: ast.ImportFrom) -> str:
        if not node.level:
            return node.module or ""
        base = m if m in packages else m.rpartition(".")[0]
        for _ in range(node.level - 1):
            base = base.rpartition(".")[0]
        return f"{base}.{node.module}" if node.module else base

    # name -> defining module, for the names a package __init__ re-exports
    reexports: dict[str, dict[str, str]] = {}
    for pkg in packages:
        table: dict[str, str] = {}
        # the lazy re-exports (LAZY_REEXPORTS) name their definitions under `if TYPE_CHECKING:`
        body = [n for node in trees[pkg].body
                for n in (node.body if isinstance(node, ast.If) and _is_type_checking(node) else [node])]
        for node in body:
            if isinstance(node, ast.ImportFrom):
                base = absolute(pkg, node)
                for a in node.names:
                    table[a.asname or a.name] = f"{base}.{a.name}" if f"{base}.{a.name}" in modules else base
        reexports[pkg] = table

    def resolve(base: str, name: str | None, seen: frozenset[str] = frozenset()) -> str:
        if name is not None and f"{base}.{name}" in modules:
            return f"{base}.{name}"
        if name is not None and base in reexports and name in reexports[base] and base not in seen:
            target = reexports[base][name]
            return target if target not in packages else resolve(target, name, seen | {base})
        return base

    graph = Graph(modules)
    for m, tree in trees.items():
        # the CLI's lazy imports (imunav.cli._lazy.lazy): `alias = lazy("imunav.x")` at module level, then
        # `alias.name` resolved like `from imunav.x import name`
        aliases = {node.targets[0].id: node.value.args[0].value for node in tree.body
                   if isinstance(node, ast.Assign) and len(node.targets) == 1 and isinstance(node.targets[0], ast.Name)
                   and isinstance(node.value, ast.Call) and isinstance(node.value.func, ast.Name)
                   and node.value.func.id == "lazy" and node.value.args and isinstance(node.value.args[0], ast.Constant)
                   and str(node.value.args[0].value).startswith(package + ".")}
        for node in ast.walk(tree) if aliases else ():
            if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id in aliases:
                base = aliases[node.value.id]
                if base in modules:
                    graph.edges.append(Import(m, resolve(base, node.attr), node.lineno, False))
    for m, tree in trees.items():
        for node, in_fn in _imports(tree):
            if isinstance(node, ast.Import):
                targets = [(a.name, None) for a in node.names]
            else:
                base = absolute(m, node)
                targets = [(base, a.name) for a in node.names]
            for base, name in targets:
                top = base.partition(".")[0]
                if top == package:
                    while base not in modules and "." in base:  # "import a.b.c" of a name, not a module
                        base = base.rpartition(".")[0]
                    target = resolve(base, name)
                    # importing a.b.c first runs a/__init__ and a/b/__init__ (those not already running for m)
                    parts = target.split(".")
                    chain = [".".join(parts[:k]) for k in range(1, len(parts))] + [target]
                    for t in chain:
                        if t != m and not m.startswith(t + ".") and not (in_fn and (m, t) in LAZY_REEXPORTS):
                            graph.edges.append(Import(m, t, node.lineno, in_fn))
                elif in_fn:
                    prev = lines[m][node.lineno - 2] if node.lineno >= 2 else ""
                    commented = "# optional:" in lines[m][node.lineno - 1] or prev.strip().startswith("# optional:")
                    graph.external_in_function.append((m, node.lineno, top, commented))
    return graph


def find_cycles(graph: Graph) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan), each sorted."""
    adj: dict[str, set[str]] = {m: set() for m in graph.modules}
    for e in graph.edges:
        adj[e.source].add(e.target)
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    out: list[list[str]] = []
    counter = 0
    for root in sorted(adj):
        if root in index:
            continue
        work = [(root, iter(sorted(adj[root])))]
        index[root] = low[root] = counter
        counter += 1
        stack.append(root)
        on_stack.add(root)
        while work:
            v, it = work[-1]
            w = next(it, None)
            if w is not None:
                if w not in index:
                    index[w] = low[w] = counter
                    counter += 1
                    stack.append(w)
                    on_stack.add(w)
                    work.append((w, iter(sorted(adj[w]))))
                elif w in on_stack:
                    low[v] = min(low[v], index[w])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[v])
            if low[v] == index[v]:
                comp = []
                while True:
                    w = stack.pop()
                    on_stack.discard(w)
                    comp.append(w)
                    if w == v:
                        break
                if len(comp) > 1:
                    out.append(sorted(comp))
    return out


def layer_of(module: str, layers: list[tuple[str, tuple[str, ...]]] = LAYERS) -> int | None:
    """Index of the layer of ``module`` (longest matching prefix), None when no layer lists it."""
    best: tuple[int, int] | None = None
    for i, (_, prefixes) in enumerate(layers):
        for p in prefixes:
            if module == p or module.startswith(p + "."):
                if best is None or len(p) > best[0]:
                    best = (len(p), i)
    return None if best is None else best[1]


def layer_violations(graph: Graph, layers: list[tuple[str, tuple[str, ...]]] = LAYERS) -> list[str]:
    """Imports from a lower layer to a higher one, and modules in no layer."""
    out = [f"{m}: in no layer (add it to LAYERS and to docs/design.md)" for m in graph.modules
           if layer_of(m, layers) is None]
    for e in graph.edges:
        a, b = layer_of(e.source, layers), layer_of(e.target, layers)
        if a is not None and b is not None and b > a:
            out.append(f"{e.source}:{e.line} imports {e.target} ({layers[a][0]} -> {layers[b][0]})")
    return out


def function_level_problems(graph: Graph, optional: frozenset[str] = OPTIONAL_IMPORTS) -> list[str]:
    """Function-level imports of the package itself or of a required dependency, or optional ones uncommented."""
    out = [f"{e.source}:{e.line} imports {e.target} inside a function (move it to module level)"
           for e in graph.edges if e.in_function]
    for m, line, top, commented in graph.external_in_function:
        if top not in optional:
            out.append(f"{m}:{line} imports {top} inside a function (not an optional dependency: move it up)")
        elif not commented:
            out.append(f"{m}:{line} imports optional {top} inside a function without a '# optional: <why>' comment")
    return sorted(out, key=lambda s: (s.split(":")[0], int(s.split(":")[1].split()[0])))


def _is_private(name: str) -> bool:
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def private_imports(src: Path, package: str, importer: str) -> list[str]:
    """Imports by the modules of ``importer`` (a subpackage such as ``imunav.cli``) of a private module or name of
    the rest of ``package``: a module path with a part, or an imported name, that starts with ``_`` (dunders
    such as ``__version__`` aside)."""
    out = []
    root = src / Path(*importer.split("."))
    for path in sorted(root.rglob("*.py")):
        m = _module_name(path, src)
        pkg = m if path.name == "__init__.py" else m.rpartition(".")[0]
        for node, _ in _imports(ast.parse(path.read_text(encoding="utf-8"), str(path))):
            if isinstance(node, ast.Import):
                pairs = [(a.name, None) for a in node.names]
            else:
                base = pkg
                for _ in range(node.level - 1):
                    base = base.rpartition(".")[0]
                mod = (f"{base}.{node.module}" if node.module else base) if node.level else (node.module or "")
                pairs = [(mod, a.name) for a in node.names]
            for mod, name in pairs:
                if mod.partition(".")[0] != package or mod == importer or mod.startswith(importer + "."):
                    continue
                if any(_is_private(part) for part in mod.split(".")) or (name is not None and _is_private(name)):
                    out.append(f"{m}:{node.lineno} imports {mod}" + (f" {name}" if name else ""))
    return out


def importers_of(graph: Graph, target: str, allowed: tuple[str, ...] = ()) -> list[str]:
    """Edges into ``target`` (a module or package, with its submodules) from outside it and outside ``allowed``."""
    def under(m: str, p: str) -> bool:
        return m == p or m.startswith(p + ".")
    return [f"{e.source}:{e.line} imports {e.target}" for e in graph.edges
            if under(e.target, target) and not under(e.source, target) and not any(under(e.source, a) for a in allowed)]


@pytest.fixture(scope="module")
def graph() -> Graph:
    return build_graph(SRC, "imunav")


def test_graph_sees_the_package(graph):
    # a broken walker would pass every check below on an empty graph
    assert len(graph.modules) > 100
    assert Import("imunav.io.csv", "imunav.timeseries", 0, False) in {
        Import(e.source, e.target, 0, e.in_function) for e in graph.edges}
    # a name imported from a package resolves to the module that defines it
    assert any(e.source == "imunav.cli.zupt" and e.target == "imunav.ins.zupt.filter" for e in graph.edges)
    # ... also a lazy re-export (imunav.io's PEP 562 __getattr__): lab.batch's `from imunav.io import read_imu`
    assert any(e.source == "imunav.lab.batch" and e.target == "imunav.io.core" for e in graph.edges)


def test_no_import_cycles(graph):
    assert find_cycles(graph) == []


def test_no_import_from_a_lower_layer_to_a_higher_one(graph):
    assert layer_violations(graph) == []


def test_function_level_imports_only_for_optional_dependencies(graph):
    assert function_level_problems(graph) == []


def test_the_cli_imports_only_public_library_names():
    assert private_imports(SRC, "imunav", "imunav.cli") == []


def test_nothing_imports_the_cli_and_nothing_below_the_lab_imports_the_lab(graph):
    assert importers_of(graph, "imunav.cli") == []
    assert importers_of(graph, "imunav.lab", allowed=("imunav.cli",)) == []


def test_a_command_module_registers_module_level_commands():
    """One way to register a command: each command (or command group) is defined at module level and
    ``register(app)`` only adds it (``app.command(NAME)(fn)`` or ``app.add_typer(group, name=NAME)``); no command
    is defined inside ``register``."""
    nested = []
    for path in sorted((SRC / "imunav" / "cli").glob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in tree.body:
            if isinstance(node, ast.FunctionDef) and node.name == "register":
                nested += [f"{path.name}: {n.name}" for n in ast.walk(node) if n is not node
                           and isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))]
    assert nested == []


def test_the_checks_fail_on_a_private_import_and_on_an_upward_import(tmp_path):
    src = _write_package(tmp_path, {
        "__init__.py": "__version__ = '1'\n",
        "_atomic.py": "def write():\n    pass\n",
        "io/__init__.py": "",
        "io/_common.py": "def helper():\n    pass\n",
        "io/csv.py": "def read():\n    pass\n\ndef _parse():\n    pass\n",
        "lab/__init__.py": "",
        "lab/runner.py": "from pkg.cli._errors import fail\n",
        "low.py": "import pkg.lab.runner\n",
        "cli/__init__.py": "",
        "cli/_errors.py": "def fail():\n    pass\n",
        "cli/cmd.py": "from pkg import __version__\nfrom pkg.io.csv import read, _parse\nfrom pkg.io import _common\n"
                      "import pkg._atomic\nfrom ._errors import fail\nfrom ..io.csv import read as r\n",
    })
    assert private_imports(src, "pkg", "pkg.cli") == [
        "pkg.cli.cmd:2 imports pkg.io.csv _parse", "pkg.cli.cmd:3 imports pkg.io _common",
        "pkg.cli.cmd:4 imports pkg._atomic"]
    g = build_graph(src, "pkg")
    assert importers_of(g, "pkg.cli") == ["pkg.lab.runner:1 imports pkg.cli", "pkg.lab.runner:1 imports pkg.cli._errors"]
    assert importers_of(g, "pkg.lab", allowed=("pkg.cli",)) == ["pkg.low:1 imports pkg.lab",
                                                               "pkg.low:1 imports pkg.lab.runner"]


#: never loaded by importing a package or a CLI command module: drawing and optional extras, imported inside
#: the functions that need them
NOT_AT_IMPORT = ("matplotlib", "torch", "dask", "distributed")

#: prints the optional packages loaded and the numba kernels compiled or loaded from the cache so far
_LOADED = (
    "import sys\n"
    "from numba.core.dispatcher import Dispatcher\n"
    "mods = sorted({{m.split('.')[0] for m in sys.modules}} & set({heavy!r}))\n"
    "ran = sorted(f'{{n}}.{{k}}' for n, m in list(sys.modules.items()) if n.startswith('imunav') "
    "for k, v in vars(m).items() if isinstance(v, Dispatcher) and v.signatures)\n"
    "print(mods, ran)\n"
)


def _run_python(code: str) -> str:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(p for p in (str(SRC), os.environ.get("PYTHONPATH")) if p)}
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=300)
    assert r.returncode == 0, r.stderr[-3000:]
    return r.stdout.strip()


def test_importing_the_packages_loads_no_optional_package_and_runs_no_kernel():
    """matplotlib, torch and dask are imported inside the functions that need them: every package (plot modules
    included) and every CLI command module (what ``imunav CMD --help`` imports) imports without them, in a fresh
    interpreter, and no numba kernel runs (or is loaded from the cache) at import: a module-level constant
    computed by a kernel costs a compilation on a cold cache."""
    modules = build_graph(SRC, "imunav").modules
    packages = sorted(m for m, p in modules.items() if p.name == "__init__.py" or m.endswith(".plot")
                      or m in ("imunav.lab.runner", "imunav.lab.batch") or m.startswith("imunav.cli."))
    code = f"import {', '.join(packages)}\n" + _LOADED.format(heavy=NOT_AT_IMPORT)
    assert _run_python(code) == "[] []"


def test_import_imunav_is_light():
    """``import imunav`` loads neither pandas nor the drawing / optional packages."""
    assert _run_python("import imunav\n" + _LOADED.format(heavy=("pandas", *NOT_AT_IMPORT))) == "[] []"


def _write_package(root: Path, files: dict[str, str]) -> Path:
    for rel, text in files.items():
        p = root / "pkg" / rel
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(text)
    return root


def test_checks_fail_on_a_synthetic_cycle_violation_and_lazy_import(tmp_path):
    src = _write_package(tmp_path, {
        "__init__.py": "",
        "low/__init__.py": "from pkg.low.a import f\n",
        "low/a.py": "def f():\n    from ..high import g\n    import numpy as np\n    return g\n",
        "high.py": "from pkg.low import f\n\ndef g():\n    # optional: drawing only\n    import matplotlib\n"
                   "    import torch\n    return f\n",
        "ok.py": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from pkg.high import g\n",
    })
    g = build_graph(src, "pkg")
    # the re-export of pkg.low resolves to pkg.low.a: a -> high -> (pkg.low/__init__ ->) a
    assert find_cycles(g) == [["pkg.high", "pkg.low", "pkg.low.a"]]
    layers = [("low", ("pkg", "pkg.low", "pkg.ok")), ("high", ("pkg.high",))]
    assert layer_violations(g, layers) == ["pkg.low.a:2 imports pkg.high (low -> high)"]
    assert function_level_problems(g) == [
        "pkg.high:6 imports optional torch inside a function without a '# optional: <why>' comment",
        "pkg.low.a:2 imports pkg.high inside a function (move it to module level)",
        "pkg.low.a:3 imports numpy inside a function (not an optional dependency: move it up)",
    ]
    assert "pkg.high: in no layer (add it to LAYERS and to docs/design.md)" in layer_violations(g, [("low", ("pkg.low",))])


def test_a_cycle_through_a_package_init_is_found(tmp_path):
    """q imports p.n, which first runs p/__init__, which imports p.m, which imports q: a cycle at run time
    (``import pkg.q`` fails) although no module names another that names it back."""
    src = _write_package(tmp_path, {
        "__init__.py": "",
        "p/__init__.py": "from pkg.p.m import f\n",
        "p/m.py": "from pkg.q import g\n\ndef f():\n    return g\n",
        "p/n.py": "",
        "q.py": "import pkg.p.n\n\ndef g():\n    return pkg.p.n\n",
    })
    assert find_cycles(build_graph(src, "pkg")) == [["pkg.p", "pkg.p.m", "pkg.q"]]
