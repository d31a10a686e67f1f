"""Every fenced example of README.md runs (issue 16, item 8).

Each ```bash and ```python block of the README is one test (its id names the
README line), run as written in a fresh working folder laid out like the
repository: ``examples/`` and ``benchmarks/`` are links to the repository's,
and ``../shared/data`` is a link to the shared data folder (``IMUNAV_DATA`` or
``../shared/data`` of the repository, found by :mod:`shared_data`).  Bash
blocks run with ``set -e -o pipefail``, so every line must exit 0; the
``imunav`` and ``python`` they call are this interpreter with this tree's
``src`` first on ``PYTHONPATH`` (a shim put first on ``PATH``), so the test
checks the checked-out code whether or not the package is installed.

How a block is run is said in the README itself, in HTML comments (invisible
on the rendered page) right before the block, so the reduction stands beside
the example it changes:

``<!-- readme-test: skip (reason) -->``
    not run; the reason is listed.
``<!-- readme-test: reduce OLD -> NEW -->``
    run with the text OLD replaced by NEW (e.g. ``--runs 100 -> --runs 5``);
    OLD must occur in the block.
``<!-- readme-test: file NAME -->``
    a ```toml block written as NAME into the working folder of every block
    (a later block uses it).
``<!-- readme-test: expect V1 V2 ... -->``
    the block's output must show each figure V (a number printed that rounds
    to V at V's decimals), so a figure quoted in the README is checked.
``<!-- readme-test: status N PREFIX -->``
    the command line that starts with PREFIX must exit with status N (a
    documented non-zero exit, e.g. a batch whose units fail the spec).
``<!-- readme-test: slow -->``
    marked ``pytest.mark.slow``.

Blocks that read the shared data skip when it is absent.  A ```toml block
without ``file`` is parsed (it must be valid TOML).  The list of skipped and
reduced blocks is printed by ``test_readme_reductions_listed`` (run pytest
with ``-s`` to see it).  Figures that only long benchmarks can regenerate are
listed, with their commands, in ``benchmarks/readme_figures.py``; its README
texts are checked here to be in the README.
"""

from __future__ import annotations

import os
import re
import shutil
import stat
import subprocess
import sys
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import pytest
from shared_data import ROOT

README = ROOT / "README.md"
TIMEOUT_S = 240  # one block; the slowest reduced block takes about a minute on a loaded 2-core machine
_DIRECTIVE = re.compile(r"<!--\s*readme-test:\s*(.*?)\s*-->")
_DATA_MARKERS = ("../shared/data", "shared:", "IMUNAV_DATA", "load_broad", "attitude run", "attitude benchmark")


@dataclass
class Block:
    line: int  # README line of the opening fence
    lang: str
    text: str
    skip: str | None = None
    reduce: list[tuple[str, str]] = field(default_factory=list)
    file: str | None = None
    expect: list[str] = field(default_factory=list)
    status: list[tuple[int, str]] = field(default_factory=list)
    slow: bool = False

    @property
    def id(self) -> str:
        return f"L{self.line}-{self.lang}"

    def runnable_text(self) -> str:
        text = self.text
        for old, new in self.reduce:
            text = text.replace(old, new)
        for code, prefix in self.status:
            text = _expect_status(text, prefix, code)
        return text


def _expect_status(text: str, prefix: str, code: int) -> str:
    """``text`` with the command that starts with ``prefix`` (and its continuation lines) required to exit
    with ``code``."""
    lines = text.split("\n")
    start = next((i for i, line in enumerate(lines) if line.startswith(prefix)), None)
    assert start is not None, f"no line starts with {prefix!r}"
    end = start
    while lines[end].rstrip().endswith("\\"):
        end += 1
    lines[start] = "if " + lines[start]
    lines[end] += (f"\nthen echo 'expected exit status {code}, got 0' >&2; false; else s=$?; [ $s -eq {code} ] || "
                   f"{{ echo \"expected exit status {code}, got $s\" >&2; false; }}; fi")
    return "\n".join(lines)


def parse_readme(path: Path = README) -> list[Block]:
    """Fenced blocks of the README with the ``readme-test`` directives just before each."""
    lines = path.read_text(encoding="utf-8").splitlines()
    blocks: list[Block] = []
    pending: list[str] = []
    i = 0
    while i < len(lines):
        s = lines[i].strip()
        m = _DIRECTIVE.fullmatch(s)
        if m:
            pending.append(m.group(1))
        elif s.startswith("```"):
            lang = s[3:].strip() or "text"
            j = i + 1
            while j < len(lines) and not lines[j].strip().startswith("```"):
                j += 1
            b = Block(i + 1, lang, "\n".join(lines[i + 1 : j]) + "\n")
            for d in pending:
                _apply(b, d)
            pending = []
            blocks.append(b)
            i = j
        elif s:
            if pending:
                raise AssertionError(f"README line {i + 1}: readme-test directive(s) {pending} not followed by a block")
        i += 1
    return blocks


def _apply(b: Block, d: str) -> None:
    word, _, rest = d.partition(" ")
    if word == "skip":
        b.skip = rest.strip().strip("()") or "no reason given"
    elif word == "reduce":
        old, sep, new = rest.partition(" -> ")
        assert sep, f"README line {b.line}: write reduce OLD -> NEW, got {d!r}"
        b.reduce.append((old, new))
    elif word == "file":
        b.file = rest.strip()
    elif word == "expect":
        b.expect = rest.split()
    elif word == "status":
        code, _, prefix = rest.partition(" ")
        b.status.append((int(code), prefix))
    elif word == "slow":
        b.slow = True
    else:
        raise AssertionError(f"README line {b.line}: unknown readme-test directive {d!r}")


BLOCKS = parse_readme()
RUN = [b for b in BLOCKS if b.lang in ("bash", "python")]


def _data_dir() -> Path:
    env = os.environ.get("IMUNAV_DATA")
    return Path(env) if env else ROOT.parent / "shared" / "data"


def _needs_data(b: Block) -> bool:
    """The block reads the shared data, itself or through a file written from another block."""
    return any(m in b.text for m in _DATA_MARKERS) or any(
        f.file in b.text and _needs_data(f) for f in BLOCKS if f.file and f is not b)


def _workdir(tmp: Path) -> tuple[Path, dict[str, str]]:
    """A folder laid out like the repository root, and the environment of the examples."""
    work = tmp / "repo"
    work.mkdir()
    for name in ("examples", "benchmarks"):
        (work / name).symlink_to(ROOT / name, target_is_directory=True)
    data = _data_dir()
    if data.is_dir():
        (tmp / "shared").mkdir()
        (tmp / "shared" / "data").symlink_to(data.resolve(), target_is_directory=True)
    shims = tmp / "bin"
    shims.mkdir()
    for name, target in (("imunav", f'"{sys.executable}" -m imunav.cli.main'), ("python", f'"{sys.executable}"')):
        p = shims / name
        p.write_text(f'#!/bin/sh\nexec {target} "$@"\n')
        p.chmod(p.stat().st_mode | stat.S_IXUSR | stat.S_IXGRP | stat.S_IXOTH)
    env = dict(os.environ)
    env["PATH"] = f"{shims}{os.pathsep}{env.get('PATH', '')}"
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT / "src"), *filter(None, [env.get("PYTHONPATH")])])
    env["IMUNAV_DATA"] = str(data)
    env["MPLBACKEND"] = "Agg"
    env["COLUMNS"] = "160"
    for b in BLOCKS:
        if b.file:
            (work / b.file).write_text(b.runnable_text(), encoding="utf-8")
    return work, env


def _params() -> list:
    return [pytest.param(b, id=b.id, marks=[pytest.mark.slow] if b.slow else []) for b in RUN]


def _figures_shown(expected: str, out: str) -> bool:
    """A number in ``out`` that rounds to ``expected`` at its number of decimals."""
    dec = len(expected.partition(".")[2])
    want = float(expected)
    return any(round(float(x), dec) == want for x in re.findall(r"-?\d+(?:\.\d+)?(?:[eE]-?\d+)?", out))


@pytest.mark.parametrize("block", _params())
def test_readme_example(block: Block, tmp_path: Path) -> None:
    if block.skip:
        pytest.skip(f"README line {block.line}: {block.skip}")
    if _needs_data(block) and not _data_dir().is_dir():
        pytest.skip(f"README line {block.line}: shared data not found at {_data_dir()} (set IMUNAV_DATA)")
    for old, _ in block.reduce:
        assert old in block.text, f"README line {block.line}: the reduction {old!r} is not in the block any more"
    work, env = _workdir(tmp_path)
    text = block.runnable_text()
    if block.lang == "bash":
        # README line of the failing command: the script's lines are the block's lines
        script = (f"set -e -o pipefail; trap 'echo \"README line $(({block.line} - 1 + LINENO))\" >&2' ERR\n"
                  f"{text}")
        cmd = ["bash", "-c", script]
    else:
        cmd = [sys.executable, "-c", text]
    try:
        res = subprocess.run(cmd, cwd=work, env=env, capture_output=True, text=True, timeout=TIMEOUT_S)
    except subprocess.TimeoutExpired:
        pytest.fail(f"README line {block.line}: the example ran past {TIMEOUT_S} s")
    out = res.stdout + res.stderr
    assert res.returncode == 0, (f"README line {block.line} ({block.lang} block) exited {res.returncode}:\n"
                                 f"{out[-4000:]}")
    missing = [v for v in block.expect if not _figures_shown(v, out)]
    assert not missing, (f"README line {block.line}: figure(s) {missing} quoted in the README are not in the "
                         f"output:\n{out[-3000:]}")


def test_readme_toml_blocks_parse() -> None:
    tomls = [b for b in BLOCKS if b.lang == "toml"]
    assert tomls
    for b in tomls:
        try:
            tomllib.loads(b.text)
        except tomllib.TOMLDecodeError as exc:
            raise AssertionError(f"README line {b.line}: not valid TOML ({exc})") from None


def test_readme_has_no_untested_block() -> None:
    """Every fenced block is bash, python or toml (a bare ``` block would not be run)."""
    other = [f"line {b.line}: {b.lang!r}" for b in BLOCKS if b.lang not in ("bash", "python", "toml")]
    assert not other, f"README blocks of no known language (mark them ```bash, ```python or ```toml): {other}"


def test_readme_reductions_listed() -> None:
    """Prints what is not run as written; fails on a directive whose text is no longer in its block."""
    skipped = sum(bool(b.skip) for b in RUN)
    reduced = sum(bool(b.reduce) and not b.skip for b in RUN)
    print(f"\nREADME: {len(BLOCKS)} fenced blocks, {len(RUN)} bash/python examples: {len(RUN) - skipped} run "
          f"({reduced} of them reduced), {skipped} skipped; {len(BLOCKS) - len(RUN)} toml")
    for b in BLOCKS:
        if b.skip:
            print(f"  skipped  line {b.line} ({b.lang}): {b.skip}")
        for old, new in b.reduce:
            print(f"  reduced  line {b.line} ({b.lang}): {old} -> {new}")
            assert old in b.text, f"README line {b.line}: reduction {old!r} is not in the block"
        if b.file:
            print(f"  file     line {b.line} ({b.lang}): written as {b.file}")
        if b.expect:
            print(f"  checks   line {b.line} ({b.lang}): figures {' '.join(b.expect)}")
        if b.slow:
            print(f"  slow     line {b.line} ({b.lang}): marked pytest.mark.slow")
        for code, prefix in b.status:
            print(f"  status   line {b.line} ({b.lang}): {prefix} ... exits {code}")


def test_readme_figures_registered() -> None:
    """Each long figure listed in benchmarks/readme_figures.py is still quoted in the README as listed."""
    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        import readme_figures
    finally:
        sys.path.pop(0)
    norm = readme_figures._normalise
    text = norm(README.read_text(encoding="utf-8"))
    missing = [f"{f.name}: {f.readme!r}" for f in readme_figures.FIGURES if norm(f.readme) not in text]
    assert not missing, ("README no longer quotes (update benchmarks/readme_figures.py with the README):\n"
                         + "\n".join(missing))


def test_shim_runs_this_tree(tmp_path: Path) -> None:
    """The ``imunav`` of the examples is the code of this checkout."""
    work, env = _workdir(tmp_path)
    res = subprocess.run(["imunav", "--version"], cwd=work, env=env, capture_output=True, text=True, timeout=60)
    assert res.returncode == 0, res.stderr
    assert shutil.which("imunav", path=env["PATH"]).startswith(str(tmp_path))
    res = subprocess.run(["python", "-c", "import imunav; print(imunav.__file__)"], cwd=work, env=env,
                         capture_output=True, text=True, timeout=60)
    assert Path(res.stdout.strip()).resolve().is_relative_to((ROOT / "src").resolve()), res.stdout


def test_lab_quick_lists_every_option() -> None:
    """The README says examples/lab_quick.toml lists every option of the simulation step; it missed remount_s
    and figures (issue 16, item 7).  An option may be shown commented out (``# or: model = ...``)."""
    from imunav.lab.steps.simulate_tests import _DEFAULTS

    text = (ROOT / "examples" / "lab_quick.toml").read_text(encoding="utf-8")
    table = tomllib.loads(text)["simulate_tests"]
    shown = set(table) | set(re.findall(r"#.*?\b(\w+) = ", text))
    assert not set(table) - set(_DEFAULTS), f"lab_quick.toml has unknown options {set(table) - set(_DEFAULTS)}"
    missing = sorted(set(_DEFAULTS) - shown)
    assert not missing, f"examples/lab_quick.toml does not list the [simulate_tests] option(s) {missing}"
    assert "`examples/lab_quick.toml` lists every option of the simulation step" in README.read_text(encoding="utf-8")
