"""The study's memory in its output folder: each stage's stored result, and the digests that vouch for it.

``DIR/.flexshaft-study/`` holds

- ``manifest.json``, the record: per stage its key and what made it (a digest of the stage's
  settings, its dependencies' keys, flexshaft's version, the SHA-256 of every file it read), the
  SHA-256 of its stored result file and the names of the files it wrote; and the SHA-256 of the
  report files (``results.json``, ``index.html``) as the last run wrote them;
- ``stages/<name>.json``, a stage's results with the SHA-256 of each of its figures and of each
  file it wrote into the folder (exports, time runs, tuned models);
- ``stages/<name>.<n>.png``, its figures (the mode viewer's data as ``.json``);
- ``lock``, held by the run writing the folder (:mod:`.folder`).

A stored result stands only when the chain of digests holds from the record down: the stage's
key is unchanged, its result file is the one the record names, and every figure and written file
is the one that result file names. Anything else - a file missing, changed, replaced by a link, a
FIFO or a device, above its ceiling, a record naming a path outside the folder - and the stage is
redone, and :class:`Found` says why.

Writes go up the chain, so that a kill at any instant leaves nothing a later run trusts wrongly:
the stage's own files (written by the stage), its figures, its result file, then the record -
rewritten whole and atomically after every stage, so a kill costs only the stage in progress.
Until the record is written it names the previous result file's digest, which a new file does not
have; any change of the record clears the report files' digests, so the report is written again.

Every file here is read as :mod:`flexshaft.system.inputs` reads an input, with ``own=True``: a regular
file only (a FIFO or a device counts as changed, it is never opened to block), no symbolic link,
within its ceiling (:data:`~flexshaft.system.inputs.STORED` for what is parsed whole,
:data:`~flexshaft.system.inputs.DIGESTED` for what is hashed a piece at a time). Nothing read is
executed; results are JSON.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import re
import stat
from dataclasses import dataclass
from pathlib import Path

from ..errors import ModelError
from ..input.cache import package_digest
from ..system.atomic import OUTPUT_MARKER, atomic_write_bytes
from ..system.inputs import DIGESTED, STORED, file_kind, open_input, read_bytes
from ..system.nesting import json_document
from ..version import __version__
from .folder import FOLDER, real_folder
from .plan import Output, Stage, slug

__all__ = ["Store", "Found", "FOLDER", "FORMAT"]

FORMAT = "flexshaft-study-cache"
_VERSION = 2  # 2: stored results vouched for by digests; records of version 1 are not used
_MANIFEST = "manifest.json"
_STAGES = "stages"
_FIGURE_FILE = re.compile(r"[a-z0-9-]*-[0-9a-f]{8}\.[0-9]+\.(png|json)")  # <name>.<n>.<type>, nothing else


def _sha(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def _shown(path: str) -> str:
    """A path for a message: relative to the working folder when that is shorter."""
    rel = os.path.relpath(path)
    return path if rel.startswith("..") else rel


def _trouble(path: Path, err: Exception) -> str:
    """Why a file of the folder could not be read: ``is missing``, ``is now a FIFO ...``, its size."""
    try:
        mode = os.lstat(path).st_mode
    except FileNotFoundError:
        return "is missing"
    except OSError:
        mode = stat.S_IFREG
    what = file_kind(mode)
    if what is not None:
        return f"is now {what}"
    return getattr(err, "message", None) or f"cannot be read ({err})"


def _hash(path, *, own: bool) -> str:
    h = hashlib.sha256()
    with open_input(path, DIGESTED, own=own) as fh:
        while piece := fh.read(1 << 20):
            h.update(piece)
    return h.hexdigest()


def _digest_input(path) -> str | None:
    """SHA-256 of an input file, or None when it is not a readable regular file within its ceiling.

    Read as an input (:func:`flexshaft.system.inputs.open_input`): a FIFO, a device or a folder is not
    opened, so it never blocks; the stage that reads it is redone and its reader names the file.
    """
    try:
        return _hash(path, own=False)
    except (ModelError, OSError):
        return None


def _digest_own(path: Path) -> tuple[str | None, str | None]:
    """SHA-256 of a file of the output folder, or None and why not."""
    try:
        return _hash(path, own=True), None
    except (ModelError, OSError) as err:
        return None, _trouble(path, err)


def _name(stage_id: str) -> str:
    """A stage's file name: readable, and unique (two ids may share a slug)."""
    return f"{slug(stage_id)[:60]}-{_sha(stage_id.encode('utf-8'))[:8]}"


def _suffix(figure: str) -> str:
    """A stored figure's file type: a PNG, or the mode viewer's data (``viewer``) as JSON."""
    return ".json" if figure == "viewer" else ".png"


def _remove(path: Path) -> None:
    """Remove a file flexshaft wrote (a link as the link; never a folder)."""
    try:
        if not stat.S_ISDIR(os.lstat(path).st_mode):
            os.unlink(path)
    except FileNotFoundError:
        pass


def _clear(path: Path) -> None:
    """Make way for a write: an entry that is not a regular file (a link, a FIFO, a device) goes.

    flexshaft's writers replace only regular files; in the study's own folder, whatever took the
    place of one of its files is removed (a link itself, never its target) and the file written anew.
    """
    try:
        mode = os.lstat(path).st_mode
    except FileNotFoundError:
        return
    if not stat.S_ISREG(mode) and not stat.S_ISDIR(mode):
        with contextlib.suppress(FileNotFoundError):
            os.unlink(path)


@dataclass(frozen=True)
class Found:
    """What the store holds for a stage now.

    Attributes
    ----------
    output : Output or None
        The stored output, when it stands.
    why : str or None
        Why it does not (``"its stored result changed since it was written"``); None when the stage
        never ran into this folder (or its output stands).
    """

    output: Output | None
    why: str | None = None


_DAMAGED = "its record is damaged"


class Store:
    """The cache of one output folder; the folder is claimed (:func:`.folder.claimed`) while it is used.

    Parameters
    ----------
    folder : Path
        The study's output folder.
    study : Path
        The study file (resolved): a folder holds one study's runs.
    """

    def __init__(self, folder: Path, study: Path):
        self.folder = Path(folder)
        self.study = Path(study)
        self.home = self.folder / FOLDER
        self.stages = self.home / _STAGES
        self.entries: dict = {}
        self.report: dict = {}
        # a link in place of stages/ would have its files read, and removed, outside the folder
        real_folder(self.stages)
        try:
            text = read_bytes(self.home / _MANIFEST, STORED, own=True).decode("utf-8")
            doc = json_document(text, _MANIFEST)
        except (ModelError, OSError, ValueError):
            doc = None  # absent, not a file, not ours: nothing is reused
        if isinstance(doc, dict) and doc.get("format") == FORMAT and doc.get("version") == _VERSION:
            entries, report = doc.get("stages"), doc.get("report")
            self.entries = dict(entries) if isinstance(entries, dict) else {}
            self.report = report if isinstance(report, dict) else {}
        self._digests: dict[str, str | None] = {}  # each input read once per run, however many stages read it

    def digest(self, path) -> str | None:
        """:func:`_digest_input` of an input, once per run."""
        key = str(path)
        if key not in self._digests:
            self._digests[key] = _digest_input(path)
        return self._digests[key]

    # --- keys ---------------------------------------------------------------------------------

    def _made(self, stage: Stage, dep_keys: dict, read) -> dict:
        """What makes a stage's key: its settings' digest, its dependencies' keys, the files it read."""
        settings = json.dumps(stage.config, sort_keys=True, default=str).encode("utf-8")
        return {
            "flexshaft": __version__,
            # the code itself: an edited install (same version) redoes the stages and their figures
            "code": package_digest("flexshaft"),
            "settings": _sha(settings),
            "deps": {d: dep_keys.get(d) for d in stage.deps},
            "read": {p: self.digest(p) for p in sorted(set(read))},
        }

    @staticmethod
    def _key(stage: Stage, made: dict) -> str:
        text = json.dumps({"format": FORMAT, "id": stage.id, **made}, sort_keys=True)
        return _sha(text.encode("utf-8"))

    def _outside(self, path) -> bool:
        """Whether an input path is absolute and outside the folder (the study's outputs are no inputs)."""
        if not (isinstance(path, str) and os.path.isabs(path)):
            return False
        try:
            root, p = self.folder.resolve(), Path(path).resolve()
        except (OSError, RuntimeError):
            return False
        return p != root and root not in p.parents

    # --- reading ------------------------------------------------------------------------------

    def lookup(self, stage: Stage, dep_keys: dict) -> Found:
        """The stage's stored output if it stands (its key unchanged, every digest holding), else why not."""
        entry = self.entries.get(stage.id)
        if entry is None:
            return Found(None)
        made = entry.get("made") if isinstance(entry, dict) else None
        read = made.get("read") if isinstance(made, dict) else None
        if not (isinstance(read, dict) and all(self._outside(p) for p in read)):
            return Found(None, _DAMAGED)
        gone = next((p for p, sha in read.items() if sha is None), None)
        if gone is not None:  # it vanished while the stage ran: what the stage read is not known
            return Found(None, f"{_shown(gone)} could not be read when it last ran")
        now = self._made(stage, dep_keys, read)
        if self._key(stage, now) != entry.get("key"):
            return Found(None, _changed(made, now))
        return self._stored(stage, entry)

    def _stored(self, stage: Stage, entry: dict) -> Found:
        name = _name(stage.id)
        path = self.stages / f"{name}.json"
        try:
            data = read_bytes(path, STORED, own=True)
        except (ModelError, OSError) as err:
            return Found(None, f"its stored result {_trouble(path, err)}")
        if _sha(data) != entry.get("sha256"):
            return Found(None, "its stored result changed since it was written")
        try:
            doc = json_document(data.decode("utf-8"), path)  # nested past the limit: a ModelError
        except ValueError:
            return Found(None, _DAMAGED)
        ok = (
            isinstance(doc, dict)
            and doc.get("id") == stage.id
            and doc.get("key") == entry.get("key")
            and isinstance(doc.get("results"), dict)
            and isinstance(doc.get("figures"), dict)
            and isinstance(doc.get("written"), dict)
        )
        if not ok:
            return Found(None, _DAMAGED)
        figures = {}
        for fig, item in doc["figures"].items():
            file = item.get("file") if isinstance(item, dict) else None
            if not (isinstance(file, str) and _FIGURE_FILE.fullmatch(file) and file.startswith(name + ".")):
                return Found(None, _DAMAGED)
            try:
                figures[fig] = read_bytes(self.stages / file, STORED, own=True)
            except (ModelError, OSError) as err:
                return Found(None, f"its figure {fig!r} {_trouble(self.stages / file, err)}")
            if _sha(figures[fig]) != item.get("sha256"):
                return Found(None, f"its figure {fig!r} changed since it was written")
        for rel, sha in doc["written"].items():
            p = self._inside(rel)
            if p is None:  # its path leaves the folder (``..``, absolute, or a link among its folders)
                return Found(None, f"its record names {rel!r}, which is not inside the folder")
            got, why = _digest_own(p)
            if got is None:
                return Found(None, f"{rel} {why}")
            if got != sha:
                return Found(None, f"{rel} changed since it was written")
        return Found(Output(doc["results"], figures, tuple(doc["written"])))

    def _inside(self, rel) -> Path | None:
        """``rel`` as a path inside the folder (no ``..``, no link among its folders), or None."""
        if not isinstance(rel, str) or not rel or os.path.isabs(rel):
            return None
        parts = Path(rel).parts
        if ".." in parts or parts[0] in (FOLDER, OUTPUT_MARKER):
            return None
        p = self.folder / rel
        try:
            root, parent = self.folder.resolve(), p.parent.resolve()
        except (OSError, RuntimeError):
            return None
        return p if parent == root or root in parent.parents else None

    def unchanged_report(self, names, study_sha: str | None) -> tuple[dict | None, str]:
        """``results.json`` as parsed when the report stands, else None; and why it does not.

        The report stands when the study file and flexshaft are those it was written by and each of
        ``names`` has the digest recorded: read as every stored file is (a FIFO or a device in
        its place counts as changed).
        """
        rec = self.report
        files = rec.get("files")
        if not isinstance(files, dict):
            return None, "the last run did not finish its report"
        if not study_sha or rec.get("study_sha256") != study_sha:
            return None, "the study file changed"
        if rec.get("flexshaft") != __version__:
            return None, "flexshaft changed"
        results = None
        for name in names:
            path = self.folder / name
            try:
                data = read_bytes(path, STORED, own=True) if name.endswith(".json") else None
                sha = _sha(data) if data is not None else _hash(path, own=True)
            except (ModelError, OSError) as err:
                return None, f"{name} {_trouble(path, err)}"
            if sha != files.get(name):
                return None, f"{name} changed since it was written"
            if data is not None:
                try:
                    results = json_document(data.decode("utf-8"), path)
                except ValueError:
                    return None, f"{name} is damaged"
        if not isinstance(results, dict):
            return None, "results.json is damaged"
        return results, ""

    # --- writing ------------------------------------------------------------------------------

    def put(self, path: Path, data: bytes) -> str:
        """Write a file of the folder atomically (a non-file in its place goes first); its SHA-256."""
        _clear(path)
        atomic_write_bytes(path, data, overwrite=True)
        return _sha(data)

    def make_way(self, stage_id: str) -> None:
        """Before a stage runs: the files it wrote last time that are no longer regular files go.

        Its writers replace regular files only; a FIFO or a link where a time run's CSV was would
        fail the stage (or, read, block it).
        """
        entry = self.entries.get(stage_id)
        written = entry.get("written") if isinstance(entry, dict) else None
        for rel in written if isinstance(written, list) else ():
            p = self._inside(rel)
            if p is not None:
                _clear(p)

    def save(self, stage: Stage, dep_keys: dict, read, out: Output, seconds: float) -> str:
        """Store a stage's output, then record it (the record is written): its key.

        ``read`` are the files it read; those inside the folder (the study's own outputs) are no
        inputs and are left out. Up the chain: figures, the result file with their digests and
        those of the files the stage wrote, then the record.
        """
        read = [q for q in (str(Path(r).resolve()) for r in read) if self._outside(q)]
        made = self._made(stage, dep_keys, read)
        key = self._key(stage, made)
        name = _name(stage.id)
        figures = {}
        for n, (fig, data) in enumerate(out.figures.items()):  # the stage's order: the report's
            file = f"{name}.{n}{_suffix(fig)}"
            figures[fig] = {"file": file, "sha256": self.put(self.stages / file, data)}
        written = {}
        for rel in out.files:
            p = self._inside(rel)
            written[rel] = _digest_own(p)[0] if p is not None else None  # None never matches: redone
        doc = {
            "format": FORMAT,
            "version": _VERSION,
            "id": stage.id,
            "key": key,
            "results": out.results,
            "figures": figures,
            "written": written,
        }
        text = json.dumps(doc, ensure_ascii=False, allow_nan=False, default=str)
        sha = self.put(self.stages / f"{name}.json", text.encode("utf-8"))
        old = self.entries.get(stage.id)
        if isinstance(old, dict):  # what its last run left that this one did not write goes with it
            self._remove_files(old, keep=set(written), keep_figures={f["file"] for f in figures.values()})
        self.entries[stage.id] = {
            "key": key,
            "sha256": sha,
            "made": made,
            "written": list(written),
            "figures": [f["file"] for f in figures.values()],
            "seconds": seconds,
        }
        self.commit()
        return key

    def _remove_files(self, entry: dict, keep=(), keep_figures=()) -> None:
        written, figures = entry.get("written"), entry.get("figures")
        for rel in written if isinstance(written, list) else ():
            p = self._inside(rel)
            if p is not None and rel not in keep:
                _remove(p)
        for file in figures if isinstance(figures, list) else ():
            if isinstance(file, str) and _FIGURE_FILE.fullmatch(file) and file not in keep_figures:
                _remove(self.stages / file)

    def forget(self, stage_id: str) -> None:
        """Forget a stage that failed (recorded at once: its old result no longer stands)."""
        if self.entries.pop(stage_id, None) is not None:
            self.commit()

    def drop(self, stage_id: str) -> None:
        """Remove a stage no longer in the study: its files first, then its entry (recorded).

        In that order, so that a kill midway leaves the entry for the next run to drop again.
        """
        entry = self.entries.get(stage_id)
        if isinstance(entry, dict):
            self._remove_files(entry)
        _remove(self.stages / f"{_name(stage_id)}.json")
        self.entries.pop(stage_id, None)
        self.commit()

    def tidy(self) -> None:
        """Remove what no entry names from ``stages/`` (left by a killed run, or a failed stage)."""
        named = set()
        for stage_id, entry in self.entries.items():
            named.add(f"{_name(stage_id)}.json")
            figures = entry.get("figures") if isinstance(entry, dict) else None
            named.update(f for f in (figures if isinstance(figures, list) else ()) if isinstance(f, str))
        try:
            present = os.listdir(self.stages)
        except OSError:
            return
        for file in present:
            if file not in named:
                _remove(self.stages / file)

    def commit(self, report: dict | None = None) -> None:
        """Write the record whole and atomically; ``report``: the report files' digests, else cleared.

        The record changes only after the files it names are written, and every change but the
        report's own clears the report's digests: the report is then written again.
        """
        self.report = report or {}
        doc = {
            "format": FORMAT,
            "version": _VERSION,
            "study": str(self.study),
            "flexshaft": __version__,
            "stages": self.entries,
            "report": self.report,
        }
        self.put(self.home / _MANIFEST, json.dumps(doc, indent=1, ensure_ascii=False).encode("utf-8"))


def _changed(old: dict, now: dict) -> str:
    """Why a stage's key changed, from what made the old one and what makes it now."""
    if old.get("flexshaft") != now["flexshaft"]:
        return f"flexshaft changed ({old.get('flexshaft')} -> {now['flexshaft']})"
    if old.get("settings") != now["settings"]:
        return "its settings in the study file changed"
    deps = old.get("deps") if isinstance(old.get("deps"), dict) else {}
    for d, key in now["deps"].items():
        if deps.get(d) != key:
            return f"{d!r}, which it builds on, changed"
    for p, sha in now["read"].items():
        if sha is None:
            return f"{_shown(p)} cannot be read"
        if old["read"].get(p) != sha:
            return f"{_shown(p)} changed"
    return _DAMAGED
