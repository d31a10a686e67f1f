"""No numba kernel takes more than :data:`MAX_ARGUMENTS` arguments: a kernel with more groups them into named tuples
(inputs, outputs, carried state, parameters), as ``imunav.ins.gins.kernels`` and ``imunav.ins.zupt.kernels`` do.

The kernels are found in the source with :mod:`ast` (nothing is imported): every function decorated with
``njit`` / ``jit`` / ``numba.njit`` / ``numba.jit`` (called or bare) under ``src/imunav``.
"""

from __future__ import annotations

import ast
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src"

MAX_ARGUMENTS = 15

_NUMBA_DECORATORS = frozenset({"njit", "jit"})


def _is_numba(decorator: ast.expr) -> bool:
    d = decorator.func if isinstance(decorator, ast.Call) else decorator
    name = d.attr if isinstance(d, ast.Attribute) else getattr(d, "id", "")
    return name in _NUMBA_DECORATORS


def _n_arguments(fn: ast.FunctionDef) -> int:
    a = fn.args
    return (len(a.posonlyargs) + len(a.args) + len(a.kwonlyargs) + (a.vararg is not None)
            + (a.kwarg is not None))


def kernel_arguments(src: Path, package: str = "imunav") -> dict[str, int]:
    """``{"module.function": number of arguments}`` of every numba kernel of ``src/<package>``."""
    out: dict[str, int] = {}
    for path in sorted((src / package).rglob("*.py")):
        module = ".".join(path.relative_to(src).with_suffix("").parts)
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
            if isinstance(node, ast.FunctionDef) and any(_is_numba(d) for d in node.decorator_list):
                out[f"{module}.{node.name}"] = _n_arguments(node)
    return out


def test_no_numba_kernel_takes_more_than_15_arguments():
    kernels = kernel_arguments(SRC)
    assert len(kernels) > 100  # the scan sees the kernels (an empty scan would pass)
    assert {k: n for k, n in kernels.items() if n > MAX_ARGUMENTS} == {}


def test_the_scan_counts_every_kind_of_argument(tmp_path):
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "k.py").write_text(
        "import numba\nfrom numba import njit\n\n"
        "@njit(cache=True)\ndef a(x, y, /, z, *rest, w, **kw):\n    pass\n\n"
        "@numba.jit\ndef b(" + ", ".join(f"x{i}" for i in range(16)) + "):\n    pass\n\n"
        "def c(" + ", ".join(f"x{i}" for i in range(20)) + "):\n    pass\n")
    assert kernel_arguments(tmp_path, "pkg") == {"pkg.k.a": 6, "pkg.k.b": 16}
