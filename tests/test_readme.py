"""Every fenced example of README.md and of the user guide runs (issue 16, item 8; issue 35).

The pages are the README (the front page) and the user guide, ``docs/guide/*.md``
(:func:`shared_data.doc_pages`).  Each ```bash and ```python block of a page is one
test (its id names the page and line, e.g. ``guide/noise:L37-bash``), run as written in a fresh working folder laid out like the
repository: ``examples/`` and ``benchmarks/`` are links to the repository's,
and ``../shared/data`` is a link to the shared data folder (``IMUNAV_DATA`` or
``../shared/data`` of the repository, found by :mod:`shared_data`).  Bash
blocks run with ``set -e -o pipefail``, so every line must exit 0; the
``imunav`` and ``python`` they call are this interpreter with this tree's
``src`` first on ``PYTHONPATH`` (a shim put first on ``PATH``), so the test
checks the checked-out code whether or not the package is installed.

How a block is run is said in the page itself, in HTML comments (invisible
on the rendered page) right before the block, so the reduction stands beside
the example it changes:

``<!-- readme-test: skip (reason) -->``
    not run; the reason is listed.
``<!-- readme-test: reduce OLD -> NEW -->``
    run with the text OLD replaced by NEW (e.g. ``--runs 100 -> --runs 5``);
    OLD must occur in the block.
``<!-- readme-test: file NAME -->``
    a ```toml block written as NAME into the working folder of every block
    of every page (a later block uses it).
``<!-- readme-test: expect V1 V2 ... -->``
    the block's output must show each figure V (a number printed that rounds
    to V at V's decimals), so a figure quoted on the page is checked.
``<!-- readme-test: status N PREFIX -->``
    the command line that starts with PREFIX must exit with status N (a
    documented non-zero exit, e.g. a batch whose units fail the spec).
``<!-- readme-test: slow -->``
    marked ``pytest.mark.slow``.
``<!-- readme-test: output -->``
    a ```text block that shows the output of the bash or python block before
    it: each number with decimals it shows is checked as an ``expect`` figure
    of that block, so a quoted output cannot drift from what the command prints.

Blocks that read the shared data skip when it is absent.  A ```toml block
without ``file`` is parsed (it must be valid TOML).  The list of skipped and
reduced blocks is printed by ``test_readme_reductions_listed`` (run pytest
with ``-s`` to see it).  Figures that only long benchmarks can regenerate are
listed, with their commands, in ``benchmarks/readme_figures.py``; its texts
are checked here to be on the README or a guide page.  ``README_V0_FIGURES``
lists every figure the README quoted before it was split into the front page
and the guide (issue 35): each must still be quoted on one of the pages.
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
from shared_data import ROOT, doc_pages, doc_text

README = ROOT / "README.md"
README_V0_FIGURES = Path(__file__).with_name("readme_v0_figures.txt")
TIMEOUT_S = 240  # one block; the slowest reduced block takes about a minute on a loaded 2-core machine
_DIRECTIVE = re.compile(r"<!--\s*readme-test:\s*(.*?)\s*-->")
_OUTPUT_FIGURE = re.compile(r"(?<![\w.])-?\d+\.\d+(?![\w.])")  # a figure of a quoted output: a decimal number
_DATA_MARKERS = ("../shared/data", "shared:", "IMUNAV_DATA", "load_broad", "attitude run", "attitude benchmark")


@dataclass
class Block:
    line: int  # page line of the opening fence
    lang: str
    text: str
    page: str = "README"  # README, or guide/<name> for docs/guide/<name>.md
    skip: str | None = None
    reduce: list[tuple[str, str]] = field(default_factory=list)
    file: str | None = None
    expect: list[str] = field(default_factory=list)
    status: list[tuple[int, str]] = field(default_factory=list)
    slow: bool = False
    output: bool = False  # a ```text block showing the previous example's output

    @property
    def id(self) -> str:
        return f"{self.page}:L{self.line}-{self.lang}" if self.page != "README" else f"L{self.line}-{self.lang}"

    @property
    def where(self) -> str:
        """The page and line, for messages: ``README line 12``, ``guide/noise line 37``."""
        return f"{self.page} line {self.line}"

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


def _page_name(path: Path) -> str:
    return "README" if path.name == "README.md" else f"guide/{path.stem}"


def parse_readme(path: Path = README) -> list[Block]:
    """Fenced blocks of a page (the README or a guide page) with the ``readme-test`` directives just before
    each."""
    page = _page_name(path)
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
            b = Block(i + 1, lang, "\n".join(lines[i + 1 : j]) + "\n", page)
            for d in pending:
                _apply(b, d)
            pending = []
            if b.output:
                run = [r for r in blocks if r.lang in ("bash", "python")]
                assert b.lang == "text" and run, f"{b.where}: an output block is a ```text block after an example"
                run[-1].expect += [x for x in _OUTPUT_FIGURE.findall(b.text) if x not in run[-1].expect]
            blocks.append(b)
            i = j
        elif s:
            if pending:
                raise AssertionError(f"{page} line {i + 1}: readme-test directive(s) {pending} not followed by a block")
        i += 1
    return blocks


def _apply(b: Block, d: str) -> None:
    word, _, rest = d.partition(" ")
    if word == "skip":
        b.skip = rest.strip().strip("()") or "no reason given"
    elif word == "reduce":
        old, sep, new = rest.partition(" -> ")
        assert sep, f"{b.where}: write reduce OLD -> NEW, got {d!r}"
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
    elif word == "output":
        b.output = True
    else:
        raise AssertionError(f"{b.where}: unknown readme-test directive {d!r}")


BLOCKS = [b for page in doc_pages() for b in parse_readme(page)]
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
        pytest.skip(f"{block.where}: {block.skip}")
    if _needs_data(block) and not _data_dir().is_dir():
        pytest.skip(f"{block.where}: shared data not found at {_data_dir()} (set IMUNAV_DATA)")
    for old, _ in block.reduce:
        assert old in block.text, f"{block.where}: the reduction {old!r} is not in the block any more"
    work, env = _workdir(tmp_path)
    text = block.runnable_text()
    if block.lang == "bash":
        # page line of the failing command: the script's lines are the block's lines
        script = (f"set -e -o pipefail; trap 'echo \"{block.page} line $(({block.line} - 1 + LINENO))\" >&2' ERR\n"
                  f"{text}")
        cmd = ["bash", "-c", script]
    else:
        cmd = [sys.executable, "-c", text]
    try:
        res = subprocess.run(cmd, cwd=work, env=env, capture_output=True, text=True, timeout=TIMEOUT_S)
    except subprocess.TimeoutExpired:
        pytest.fail(f"{block.where}: the example ran past {TIMEOUT_S} s")
    out = res.stdout + res.stderr
    assert res.returncode == 0, (f"{block.where} ({block.lang} block) exited {res.returncode}:\n"
                                 f"{out[-4000:]}")
    missing = [v for v in block.expect if not _figures_shown(v, out)]
    assert not missing, (f"{block.where}: figure(s) {missing} quoted on the page are not in the "
                         f"output:\n{out[-3000:]}")


def test_readme_toml_blocks_parse() -> None:
    tomls = [b for b in BLOCKS if b.lang == "toml"]
    assert tomls
    for b in tomls:
        try:
            tomllib.loads(b.text)
        except tomllib.TOMLDecodeError as exc:
            raise AssertionError(f"{b.where}: not valid TOML ({exc})") from None


def test_readme_has_no_untested_block() -> None:
    """Every fenced block is bash, python or toml, or the text of an example's output, or a directive of the site
    (```{toctree}: MyST's syntax, not an example); a bare ``` block would not be run."""
    other = [f"{b.where}: {b.lang!r}" for b in BLOCKS if b.lang not in ("bash", "python", "toml")
             and not (b.lang == "text" and b.output) and not (b.page != "README" and b.lang.startswith("{"))]
    assert not other, ("blocks of no known language (mark them ```bash, ```python or ```toml, or an output "
                       f"```text with <!-- readme-test: output -->): {other}")


def test_readme_reductions_listed() -> None:
    """Prints what is not run as written; fails on a directive whose text is no longer in its block."""
    skipped = sum(bool(b.skip) for b in RUN)
    reduced = sum(bool(b.reduce) and not b.skip for b in RUN)
    print(f"\nREADME and guide: {len(BLOCKS)} fenced blocks, {len(RUN)} bash/python examples: {len(RUN) - skipped} run "
          f"({reduced} of them reduced), {skipped} skipped; {sum(b.lang == 'toml' for b in BLOCKS)} toml, "
          f"{sum(b.output for b in BLOCKS)} quoted outputs checked")
    for b in BLOCKS:
        if b.skip:
            print(f"  skipped  {b.where} ({b.lang}): {b.skip}")
        for old, new in b.reduce:
            print(f"  reduced  {b.where} ({b.lang}): {old} -> {new}")
            assert old in b.text, f"{b.where}: reduction {old!r} is not in the block"
        if b.file:
            print(f"  file     {b.where} ({b.lang}): written as {b.file}")
        if b.expect:
            print(f"  checks   {b.where} ({b.lang}): figures {' '.join(b.expect)}")
        if b.slow:
            print(f"  slow     {b.where} ({b.lang}): marked pytest.mark.slow")
        for code, prefix in b.status:
            print(f"  status   {b.where} ({b.lang}): {prefix} ... exits {code}")


def test_readme_figures_registered() -> None:
    """Each long figure listed in benchmarks/readme_figures.py is still quoted, as listed, in the README or on a
    guide page."""
    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        import readme_figures
    finally:
        sys.path.pop(0)
    norm = readme_figures._normalise
    text = norm(doc_text())
    missing = [f"{f.name}: {f.readme!r}" for f in readme_figures.FIGURES if norm(f.readme) not in text]
    assert not missing, ("README and guide no longer quote (update benchmarks/readme_figures.py with the README):\n"
                         + "\n".join(missing))


def test_readme_v0_figures_still_quoted() -> None:
    """Every figure of the README before the split (issue 35: front page + user guide) is still quoted on the README
    or a guide page, so moving the text lost none."""
    figures = [ln.strip() for ln in README_V0_FIGURES.read_text(encoding="utf-8").splitlines()
               if ln.strip() and not ln.startswith("#")]
    assert len(figures) > 500
    text = " ".join(doc_text().split())
    missing = [f for f in figures if f not in text]
    assert not missing, f"figures of the README before the split no longer quoted anywhere: {missing}"


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
    assert "`examples/lab_quick.toml` lists every option of the simulation step" in doc_text()
