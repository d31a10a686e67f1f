"""Run folders: the output folders of ``imunav lab`` and ``imunav batch`` carry a manifest.

A run (:class:`RunFolder`, a context manager) owns its folder, and only what it wrote there:

* **Start.**  The folder must be new, empty, or hold only hidden files.  A
  folder that holds another run -- a ``manifest.json``, the hidden marker
  ``.imunav-run.json`` of a run that is still going or was killed, a
  ``FAILED`` file -- or any other non-hidden file is refused
  (:class:`~imunav.errors.RunFolderError`) unless ``overwrite=True``, which
  removes only the files that belong to imunav runs: those listed in the
  manifest (and nested run folders such as ``batch/calibration``), or, for a
  run that did not finish, those listed in its file log.  When the folder
  holds any file no run lists (a user's notes put into a killed run's
  folder, say), ``overwrite`` refuses and names them; nothing outside the
  folder is touched, and a folder that is the file system's root, the home
  folder, the working folder (or one of its parents) or that holds an input
  of the run is never cleared.  Hidden temporary files (``.<name>.*.tmp*``,
  left by a killed atomic write) are removed.  The marker is created
  exclusively (``O_EXCL``): of two runs started together on one folder, one
  is refused.
* **During the run.**  Every file the run writes (through
  :func:`imunav.files.atomic_path`, or a path from
  :meth:`imunav.lab.steps.LabContext.path`) is first recorded in the hidden file
  log ``.imunav-run.files`` (:func:`imunav.files.claim_run_file`): a run
  killed at any point (SIGKILL included) leaves a folder that says which
  files are its own.
* **Finish.**  The run checks that the marker is still its own (a concurrent
  run with ``overwrite`` would have replaced it: the folder then holds mixed
  files, and no manifest is written), lists every non-hidden file with its
  size and SHA-256, and writes ``manifest.json`` LAST and atomically (run id,
  kind, seed, parameters, command line, start and end times, files); then
  it removes the marker and the file log.
* **Failure (all or nothing).**  A run that fails or is interrupted (an
  exception, SIGINT) removes every file it wrote and leaves only ``FAILED``,
  a text file with the run id, the time and the error message (and the
  hidden marker that says ``FAILED`` is the run's): no partial result looks
  complete.  A run that fails before writing any file, in a folder that was
  new or empty, leaves the folder as it found it.

Readers (:func:`trusted_files`, used by ``batch calibrate`` / ``batch noise``)
trust only the files of a complete manifest, checked against their size and
SHA-256; a folder with a marker and no manifest (a killed, failed or running
run) is refused; a folder with neither is a plain folder of the user's files
(hidden files ignored).
"""

from __future__ import annotations

import contextlib
import datetime as _dt
import errno
import hashlib
import json
import os
import shutil
import socket
import sys
import uuid
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from imunav import __version__
from imunav.errors import RunFolderError
from imunav.files import RUN_FILES, RUN_MARKER, check_interrupt, jsonable, read_json, write_json

__all__ = ["FAILED", "FILES", "MANIFEST", "MARKER", "Manifest", "RunFolder", "read_manifest", "trusted_files", "sha256_file"]

MANIFEST = "manifest.json"
MARKER = RUN_MARKER
#: The run's file log (hidden): the files a run that has not finished wrote, one JSON string a line.
FILES = RUN_FILES
#: What a failed or interrupted run leaves: a text file with the run id, the time and the message.
FAILED = "FAILED"
_FORMAT = "imunav-run-manifest"
_VERSION = 1


def _now() -> str:
    return _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")


def sha256_file(path: str | os.PathLike[str]) -> str:
    """SHA-256 (hex) of a file's bytes (FIPS 180-4).

    Parameters
    ----------
    path : str or os.PathLike
        The file.

    Returns
    -------
    str
        64 hexadecimal characters.
    """
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _is_temp(name: str) -> bool:
    """A hidden temporary file of :func:`imunav.files.atomic_path` (``.<name>.<random>.tmp<suffix>``)."""
    return name.startswith(".") and ".tmp" in name and name not in (MARKER, FILES)


def _visible_files(root: Path) -> list[Path]:
    """Non-hidden files under ``root`` (hidden files and folders skipped; symlinks listed, not followed)."""
    out = []
    for dirpath, dirnames, filenames in os.walk(root):
        dirnames[:] = sorted(d for d in dirnames if not d.startswith("."))
        out += [Path(dirpath) / f for f in sorted(filenames) if not f.startswith(".")]
    return out


def _remove_temp_files(root: Path) -> list[Path]:
    gone = []
    for dirpath, _dirnames, filenames in os.walk(root):
        for f in filenames:
            if _is_temp(f):
                with contextlib.suppress(FileNotFoundError):
                    (Path(dirpath) / f).unlink()
                    gone.append(Path(dirpath) / f)
    return gone


@dataclass(frozen=True)
class Manifest:
    """A run folder's ``manifest.json`` (see the module docstring).

    Attributes
    ----------
    folder : pathlib.Path
        The run folder.
    run_id : str
        Unique id of the run.
    kind : str
        What ran (``"lab"``, ``"batch-simulate"``, ...).
    seed : int or None
        The run's seed.
    created, finished : str
        Start and end times, ISO 8601 UTC.
    files : list of dict
        Every file written: ``path`` (relative), ``size`` (bytes), ``sha256``.
    parameters : dict
        The run's parameters / configuration.
    argv : list of str
        The command line.
    """

    folder: Path
    run_id: str
    kind: str
    seed: int | None
    created: str
    finished: str
    files: list[dict[str, Any]]
    parameters: dict[str, Any] = field(default_factory=dict)
    argv: list[str] = field(default_factory=list)

    def paths(self) -> list[Path]:
        """The listed files as paths inside the folder.

        Returns
        -------
        list of pathlib.Path
            ``folder / file["path"]`` for every listed file.
        """
        return [self.folder / f["path"] for f in self.files]

    def to_dict(self) -> dict[str, Any]:
        """The ``manifest.json`` content.

        Returns
        -------
        dict
            ``format``, ``version``, ``run_id``, ``kind``, ``seed``, ``created``, ``finished``, ``parameters``,
            ``argv``, ``files``.
        """
        return {"format": _FORMAT, "version": _VERSION, "run_id": self.run_id, "kind": self.kind, "seed": self.seed,
                "created": self.created, "finished": self.finished, "parameters": self.parameters,
                "argv": self.argv, "files": self.files}


def _inside(root: Path, rel: str) -> Path:
    p = (root / rel).resolve()
    if rel.startswith(("/", "\\")) or ".." in Path(rel).parts or root.resolve() not in (p, *p.parents):
        raise RunFolderError(f"{root / MANIFEST}: the file entry {rel!r} points outside the run folder; the manifest "
                             "is damaged or forged: re-run into a new folder")
    return root / rel


def read_manifest(folder: str | os.PathLike[str], *, verify: bool = True) -> Manifest | None:
    """The manifest of a run folder; ``None`` for a plain folder (no manifest, no marker).

    Parameters
    ----------
    folder : str or os.PathLike
        The folder.
    verify : bool
        Check every listed file's size and SHA-256.

    Returns
    -------
    Manifest or None
        The manifest.

    Raises
    ------
    RunFolderError
        For an incomplete run (marker without manifest), a damaged manifest, or (``verify``) a listed file
        that is missing or whose size / SHA-256 differ.
    """
    root = Path(folder)
    mp = root / MANIFEST
    if not mp.is_file():
        if (root / MARKER).exists():
            mk = _marker(root)
            started = mk.get("started", "?")
            if mk.get("failed") is not None:
                raise RunFolderError(
                    f"{root} holds a run that failed (started {started}): {mk.get('failed')}; its files were removed "
                    f"({FAILED} says why): re-run it with --overwrite (overwrite=True)")
            raise RunFolderError(
                f"{root} holds an incomplete run (started {started}, no {MANIFEST}): it was killed, failed, or is "
                "still running, and its files may be partial or mixed; re-run it with --overwrite (overwrite=True)"
            )
        return None

    d = read_json(mp, "run manifest")
    if not isinstance(d, dict) or d.get("format") != _FORMAT or not isinstance(d.get("files"), list):
        raise RunFolderError(f"{mp} is not an imunav run manifest; re-run into a new folder")
    try:
        files = [{"path": str(f["path"]), "size": int(f["size"]), "sha256": str(f["sha256"])} for f in d["files"]]
    except (KeyError, TypeError, ValueError):
        raise RunFolderError(f"{mp}: a file entry lacks path / size / sha256; re-run into a new folder") from None
    m = Manifest(root, str(d.get("run_id")), str(d.get("kind")), d.get("seed"), str(d.get("created")),
                 str(d.get("finished")), files, dict(d.get("parameters") or {}), list(d.get("argv") or []))
    for f in files:
        p = _inside(root, f["path"])
        if verify:
            if not p.is_file():
                raise RunFolderError(f"{p} is listed in {mp} (run {m.run_id}) but missing; the folder was changed "
                                     "after the run: re-run it with --overwrite")
            if p.stat().st_size != f["size"] or sha256_file(p) != f["sha256"]:
                raise RunFolderError(f"{p} differs from {mp} (run {m.run_id}: size / sha256); another run or a user "
                                     "changed it after the run: re-run it with --overwrite")
    return m


def trusted_files(folder: str | os.PathLike[str]) -> list[Path] | None:
    """Files a reader of ``folder`` may use: those of its verified manifest, or ``None`` for a plain folder.

    Parameters
    ----------
    folder : str or os.PathLike
        The folder.

    Returns
    -------
    list of pathlib.Path or None
        The verified files.

    Raises
    ------
    RunFolderError
        For an incomplete or damaged run folder (see :func:`read_manifest`).
    """
    m = read_manifest(folder)
    return None if m is None else m.paths()


def _marker(root: Path) -> dict[str, Any]:
    try:
        d = json.loads((root / MARKER).read_text(encoding="utf-8"))
        return d if isinstance(d, dict) else {}
    except (OSError, ValueError):
        return {}


def _logged(root: Path) -> set[str]:
    """The relative paths of a run's file log (a line cut by a kill is skipped)."""
    try:
        text = (root / FILES).read_text(encoding="utf-8")
    except OSError:
        return set()
    out = set()
    for line in text.splitlines():
        try:
            rel = json.loads(line)
        except ValueError:
            continue
        if isinstance(rel, str) and rel:
            out.add(Path(os.path.normpath(rel)).as_posix())
    return out


def _owned(root: Path) -> tuple[list[Path], list[Path]]:
    """(paths that belong to imunav runs and may be removed, non-hidden files that belong to none)."""
    mine: list[Path] = []
    foreign: list[Path] = []
    listed: set[str] = set()
    if (root / MANIFEST).is_file():
        try:
            m = read_manifest(root, verify=False)
        except (RunFolderError, ValueError):
            m = None
        if m is None:
            return [], [root / MANIFEST]
        # compared as written (relative, not resolved): a user's symlink to a listed file is not listed
        listed = {Path(os.path.normpath(f["path"])).as_posix() for f in m.files}
        mine.append(root / MANIFEST)
    elif (root / MARKER).exists():
        # a run that did not finish: only the files its log names (and FAILED when it failed) are its own
        listed = _logged(root)
        if _marker(root).get("failed") is not None:
            listed.add(FAILED)
    for entry in sorted(root.iterdir()):
        if entry.name == MANIFEST:
            continue  # listed in ``mine`` above when valid
        if entry.name.startswith("."):
            if _is_temp(entry.name) or entry.name in (MARKER, FILES):
                mine.append(entry)
            continue
        if entry.is_dir() and not entry.is_symlink():
            if (entry / MANIFEST).exists() or (entry / MARKER).exists():
                sub_mine, sub_foreign = _owned(entry)
                mine += sub_mine
                foreign += sub_foreign
                continue
            for p in _visible_files(entry):
                (mine if p.relative_to(root).as_posix() in listed else foreign).append(p)
            mine += [Path(d) / f for d, _, fs in os.walk(entry) for f in fs if _is_temp(f)]
        else:
            (mine if entry.relative_to(root).as_posix() in listed else foreign).append(entry)
    return mine, foreign


def _protected(root: Path, inputs: Iterable[str | os.PathLike[str] | None]) -> str | None:
    r = root.resolve()
    cwd = Path.cwd().resolve()
    if r == Path(r.anchor) or r == Path.home().resolve():
        return "it is the file system's root or the home folder"
    if r == cwd or r in cwd.parents:
        return "it is the working folder or one of its parents"
    for p in inputs:
        if p is None:
            continue
        q = Path(p).expanduser().resolve()
        if r == q or r in q.parents:
            return f"it holds an input of this run ({p})"
    return None


def _clear(root: Path, inputs: Iterable[str | os.PathLike[str] | None]) -> None:
    why = _protected(root, inputs)
    if why:
        raise RunFolderError(f"--overwrite refuses to clear {root}: {why}; choose another output folder")
    mine, foreign = _owned(root)
    if foreign:
        shown = ", ".join(str(p.relative_to(root)) for p in foreign[:5]) + (" ..." if len(foreign) > 5 else "")
        raise RunFolderError(
            f"{root} holds {len(foreign)} file(s) that no imunav run manifest or file log lists ({shown}); --overwrite "
            "removes only the files imunav runs wrote: move those files away or choose another output folder"
        )
    _remove(root, mine)


def _remove(root: Path, paths: Iterable[Path]) -> None:
    """Remove ``paths`` (files, links, folders) inside ``root``, then the folders they leave empty."""
    emptied: set[Path] = set()
    for p in paths:
        if p.is_symlink() or p.is_file():
            with contextlib.suppress(FileNotFoundError):
                p.unlink()
            emptied.update(d for d in p.parents if d != root and root in d.parents)
        elif p.is_dir():
            shutil.rmtree(p)
    # only the folders that held removed files, deepest first, and only when now empty
    for d in sorted(emptied, key=lambda d: -len(d.parts)):
        if d.is_dir() and not d.is_symlink() and not any(d.iterdir()):
            d.rmdir()


class RunFolder:
    """Context manager for a run that writes a folder (see the module docstring).

    Parameters
    ----------
    folder : str or os.PathLike
        The run folder.
    kind : str
        What runs (``"lab"``, ``"batch-simulate"``, ...), recorded in the manifest.
    seed : int, optional
        The run's seed (None when it has none).
    parameters : mapping, optional
        The run's parameters / configuration (JSON types), recorded in the manifest.
    overwrite : bool
        Clear a folder that holds another imunav run (rules in the module docstring) instead of refusing.
    inputs : iterable of str or os.PathLike
        Input files of the run: a folder holding one of them is never cleared.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp()) / "run"
    >>> with RunFolder(d, "demo", seed=0) as run:
    ...     _ = (d / "a.txt").write_text("a")
    >>> read_manifest(d).files[0]["path"]
    'a.txt'
    """

    def __init__(self, folder: str | os.PathLike[str], kind: str, *, seed: int | None = None,
                 parameters: Mapping[str, Any] | None = None, overwrite: bool = False,
                 inputs: Iterable[str | os.PathLike[str] | None] = ()) -> None:
        self.folder = Path(folder)
        self.kind = kind
        self.seed = None if seed is None else int(seed)
        self.parameters = dict(parameters or {})
        self.overwrite = bool(overwrite)
        self.inputs = list(inputs)
        self.run_id = str(uuid.uuid4())
        self.created = ""
        self.manifest: Manifest | None = None
        self._made = False
        self._cleared = False
        self._dirs_before: set[Path] = set()

    # ------------------------------------------------------------------ start
    def start(self) -> "RunFolder":
        """Claim the folder: check it, clear it with ``overwrite``, and create the marker exclusively.

        Called by ``with RunFolder(...)``.

        Returns
        -------
        RunFolder
            ``self``.

        Raises
        ------
        RunFolderError
            If the folder holds another run or foreign files and may not be cleared, or another run claims it.
        NotADirectoryError
            If the path is a file.
        """
        root = self.folder
        if root.exists() and not root.is_dir():
            raise NotADirectoryError(errno.ENOTDIR, "the run folder is a file; give a folder", str(root))
        self._made = not root.exists()
        root.mkdir(parents=True, exist_ok=True)
        busy = (root / MANIFEST).exists() or (root / MARKER).exists() or any(
            not p.name.startswith(".") for p in root.iterdir())
        if busy:
            if not self.overwrite:
                raise RunFolderError(self._busy_message())
            _clear(root, self.inputs)
            self._cleared = True
        _remove_temp_files(root)
        self._dirs_before = {Path(d) for d, _, _ in os.walk(root)}
        self.created = _now()
        marker = {"run_id": self.run_id, "kind": self.kind, "pid": os.getpid(), "host": socket.gethostname(),
                  "started": self.created}
        try:
            fd = os.open(root / MARKER, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
        except FileExistsError:
            raise RunFolderError(f"{root}: another run started in this folder at the same time; wait for it to end, "
                                 "or choose another folder") from None
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            json.dump(marker, fh)
        (root / FILES).write_text("", encoding="utf-8")
        return self

    def _busy_message(self) -> str:
        root = self.folder
        if (root / MANIFEST).exists():
            what = "a finished run (manifest.json)"
            with contextlib.suppress(Exception):
                m = read_manifest(root, verify=False)
                if m is not None:
                    what = f"the finished run {m.run_id} ({m.kind}, {m.finished})"
        elif (root / MARKER).exists() and _marker(root).get("failed") is not None:
            mk = _marker(root)
            what = f"a run that failed (run {mk.get('run_id', '?')}, {mk.get('kind', '?')}: {mk.get('failed')})"
        elif (root / MARKER).exists():
            mk = _marker(root)
            what = (f"a run that is still going or was killed (run {mk.get('run_id', '?')}, {mk.get('kind', '?')}, "
                    f"started {mk.get('started', '?')} by pid {mk.get('pid', '?')})")
        else:
            names = [p.name for p in sorted(root.iterdir()) if not p.name.startswith(".")]
            what = f"other files ({', '.join(names[:5])}{' ...' if len(names) > 5 else ''})"
        return (f"the output folder {root} holds {what}; writing into it would mix two runs: choose a new folder, "
                "or pass --overwrite (overwrite=True) to clear that run first")

    # ----------------------------------------------------------------- finish
    def finish(self) -> Manifest:
        """Check the folder is still this run's, then write the manifest (last, atomically) and drop the marker.

        Called when the ``with`` block ends without an exception.

        Returns
        -------
        Manifest
            The manifest written.

        Raises
        ------
        RunFolderError
            If another run replaced the marker (the folder holds mixed files; no manifest is written).
        """

        root = self.folder
        mk = _marker(root)
        if mk.get("run_id") != self.run_id:
            raise RunFolderError(
                f"{root}: another run ({mk.get('run_id', 'marker removed')}) took over this folder while run "
                f"{self.run_id} was writing it; the folder holds mixed files and gets no manifest: re-run with --overwrite"
            )
        files = []
        for p in _visible_files(root):
            if p.name == MANIFEST and p.parent == root:
                continue
            files.append({"path": p.relative_to(root).as_posix(), "size": p.stat().st_size, "sha256": sha256_file(p)})
        m = Manifest(root, self.run_id, self.kind, self.seed, self.created, _now(), files,
                     jsonable(self.parameters), list(map(str, sys.argv)))
        d = m.to_dict()
        d["imunav"] = __version__
        write_json(root / MANIFEST, d)
        for name in (MARKER, FILES):
            with contextlib.suppress(FileNotFoundError):
                (root / name).unlink()
        self.manifest = m
        return m

    def fail(self, message: str) -> None:
        """Remove every file this run wrote (its file log) and leave ``FAILED`` with ``message``.

        Called when the ``with`` block ends with an exception or an interrupt.  Nothing happens when another
        run took the folder over (its marker is not this run's).

        Parameters
        ----------
        message : str
            Why the run failed (one line).
        """
        root = self.folder
        _remove_temp_files(root)
        mk = _marker(root)
        if mk.get("run_id") != self.run_id:
            return
        logged = sorted(_logged(root))
        _remove(root, [_inside(root, rel) for rel in logged if rel != FAILED])
        for d, _, _ in sorted(os.walk(root), key=lambda w: -len(Path(w[0]).parts)):
            # folders the run made and left empty (e.g. figures/ before its first figure)
            if Path(d) not in self._dirs_before and not os.listdir(d):
                os.rmdir(d)
        if not logged and not self._cleared:
            # it wrote nothing into a folder that was new or empty: leave the folder as it was found
            for name in (MARKER, FILES):
                with contextlib.suppress(FileNotFoundError):
                    (root / name).unlink()
            if self._made and not any(root.iterdir()):
                root.rmdir()
            return
        when = _now()
        msg = " ".join(str(message).split()) or "failed"
        (root / FAILED).write_text(
            f"imunav run {self.run_id} ({self.kind}) started {self.created} failed at {when}: {msg}\n"
            f"Its files were removed. Re-run with --overwrite (overwrite=True) to replace this folder.\n",
            encoding="utf-8")
        mk.update({"failed": msg, "finished": when})
        tmp = root / f".{MARKER}.tmp"
        tmp.write_text(json.dumps(mk), encoding="utf-8")
        os.replace(tmp, root / MARKER)
        with contextlib.suppress(FileNotFoundError):
            (root / FILES).unlink()

    def __enter__(self) -> "RunFolder":
        return self.start()

    def __exit__(self, et: Any, ev: Any, tb: Any) -> bool:
        if et is None:
            try:
                check_interrupt()  # an interrupt swallowed during the run: the run did not complete
            except KeyboardInterrupt:
                with contextlib.suppress(OSError, RunFolderError):
                    self.fail("interrupted")
                raise
            self.finish()
            return False
        # on an error or an interrupt: the files of this run go, FAILED stays (all or nothing)
        why = "interrupted" if isinstance(ev, KeyboardInterrupt) else f"{et.__name__}: {ev}"
        with contextlib.suppress(OSError, RunFolderError):
            self.fail(why)
        return False
