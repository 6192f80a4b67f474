"""The study's memory in its output folder: each stage's key, what it read and wrote, its results.

``DIR/.flexshaft-study/manifest.json`` records, per stage, its key and the files it read and
wrote with their SHA-256; ``DIR/.flexshaft-study/stages/<slug>.json`` its results and
``.../<slug>.<figure>.png`` its figures. A stage's key is a digest of its settings, its
dependencies' keys, flexshaft's version and the digests of the files it read the last time it
ran: when that key is unchanged and every file it wrote is still there unchanged, its stored
results stand and it is not run (a file it read that changed, or vanished, changes the key).

The manifest is flexshaft's own file, but the folder may have been tampered with: a manifest or
stored result that does not parse, or names paths outside the folder, counts as absent (the
stages run again); nothing in it is executed.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

from ..atomic import atomic_write_bytes, atomic_write_text
from ..version import __version__
from .plan import Output, Stage, slug

__all__ = ["Store", "digest_file", "FOLDER", "FORMAT"]

FOLDER = ".flexshaft-study"
FORMAT = "flexshaft-study-cache"
_VERSION = 1
#: A stored stage result larger than this is not trusted as ours (bytes).
_MAX_STORED = 256 << 20


def digest_file(path) -> str | None:
    """SHA-256 of a file's bytes, or None when it is not a readable regular file."""
    h = hashlib.sha256()
    try:
        with open(path, "rb") as fh:
            while piece := fh.read(1 << 20):
                h.update(piece)
    except (OSError, ValueError):
        return None
    return h.hexdigest()


def _read_json(path: Path):
    try:
        if path.is_symlink() or path.stat().st_size > _MAX_STORED:
            return None
        from ..nesting import json_document

        # nested past the limit: a ModelError, so a ValueError - a damaged entry, as any other
        return json_document(path.read_text(encoding="utf-8"), path)
    except (OSError, ValueError, UnicodeDecodeError):
        return None


class Store:
    """The cache of one output folder.

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
        doc = _read_json(self.home / "manifest.json")
        ok = isinstance(doc, dict) and doc.get("format") == FORMAT and doc.get("version") == _VERSION
        self.previous_study = doc.get("study") if isinstance(doc, dict) else None
        entries = doc.get("stages") if ok else None
        self.entries: dict = dict(entries) if isinstance(entries, dict) else {}
        self.report = doc.get("report") if ok and isinstance(doc.get("report"), dict) else {}
        self._digests: dict[str, str | None] = {}  # each input read once per run, however many stages read it

    def digest(self, path) -> str | None:
        """:func:`digest_file` of an input, once per run."""
        key = str(path)
        if key not in self._digests:
            self._digests[key] = digest_file(path)
        return self._digests[key]

    @staticmethod
    def owner(folder: Path) -> str | None:
        """The study file whose run a folder holds (from its manifest), or None."""
        doc = _read_json(Path(folder) / FOLDER / "manifest.json")
        study = doc.get("study") if isinstance(doc, dict) else None
        return study if isinstance(study, str) else None

    # --- keys ---------------------------------------------------------------------------------

    @staticmethod
    def key(stage: Stage, dep_keys: dict, read: dict) -> str:
        """The stage's key from its settings, its dependencies' keys and ``read`` (path -> digest)."""
        doc = {
            "format": FORMAT,
            "flexshaft": __version__,
            "id": stage.id,
            "config": stage.config,
            "deps": {d: dep_keys.get(d) for d in stage.deps},
            "read": read,
        }
        text = json.dumps(doc, sort_keys=True, default=str)
        return hashlib.sha256(text.encode()).hexdigest()

    def current_key(self, stage: Stage, dep_keys: dict) -> str | None:
        """The key the stage would have now, from the files it read last time; None if never run."""
        entry = self.entries.get(stage.id)
        if not isinstance(entry, dict) or not isinstance(entry.get("read"), list):
            return None
        read = {str(p): self.digest(p) for p in entry["read"] if isinstance(p, str)}
        return self.key(stage, dep_keys, read)

    def stored(self, stage: Stage, key: str | None) -> Output | None:
        """The stage's stored output when ``key`` matches and everything it wrote is intact."""
        entry = self.entries.get(stage.id)
        if key is None or not isinstance(entry, dict) or entry.get("key") != key:
            return None
        written = entry.get("written")
        if not isinstance(written, dict):
            return None
        for rel, sha in written.items():
            p = self._inside(rel)
            if p is None or digest_file(p) != sha:
                return None
        doc = _read_json(self.home / "stages" / f"{slug(stage.id)}.json")
        if not isinstance(doc, dict) or not isinstance(doc.get("results"), dict):
            return None
        figures = {}
        for name in doc.get("figures", []):
            p = self.home / "stages" / f"{slug(stage.id)}.{slug(name)}{_suffix(name)}"
            try:
                figures[name] = p.read_bytes()
            except OSError:
                return None
        return Output(doc["results"], figures, tuple(written))

    def _inside(self, rel) -> Path | None:
        """``rel`` as a path inside the folder, or None (a manifest naming ``../x`` is not ours)."""
        if not isinstance(rel, str):
            return None
        p = (self.folder / rel).resolve()
        root = self.folder.resolve()
        return p if root in p.parents else None

    # --- writing ------------------------------------------------------------------------------

    def save(self, stage: Stage, key: str, read: list[str], out: Output, seconds: float) -> None:
        """Store a stage's output and its entry (the manifest itself is written by :meth:`commit`)."""
        name = slug(stage.id)
        (self.home / "stages").mkdir(parents=True, exist_ok=True)
        doc = {"id": stage.id, "results": out.results, "figures": sorted(out.figures)}
        text = json.dumps(doc, ensure_ascii=False, allow_nan=False, default=str)
        atomic_write_text(self.home / "stages" / f"{name}.json", text, overwrite=True)
        for fig, png in out.figures.items():
            path = self.home / "stages" / f"{name}.{slug(fig)}{_suffix(fig)}"
            atomic_write_bytes(path, png, overwrite=True)
        written = {rel: digest_file(self.folder / rel) for rel in out.files}
        self.entries[stage.id] = {
            "key": key,
            "read": sorted(set(read)),
            "written": written,
            "seconds": seconds,
        }

    def forget(self, stage_id: str) -> None:
        """Drop a stage's entry (it failed, or it is no longer in the study)."""
        self.entries.pop(stage_id, None)

    def drop(self, stage_id: str) -> None:
        """Forget a stage no longer in the study and remove the files it wrote (regular files only)."""
        entry = self.entries.pop(stage_id, None)
        written = entry.get("written") if isinstance(entry, dict) else None
        for rel in written if isinstance(written, dict) else ():
            p = self._inside(rel)
            if p is not None and p.is_file() and not p.is_symlink():
                p.unlink()

    def commit(self, report: dict | None = None) -> None:
        """Write the manifest."""
        if report is not None:
            self.report = report
        self.home.mkdir(exist_ok=True)
        doc = {
            "format": FORMAT,
            "version": _VERSION,
            "study": str(self.study),
            "flexshaft": __version__,
            "stages": self.entries,
            "report": self.report,
        }
        atomic_write_text(
            self.home / "manifest.json", json.dumps(doc, indent=1, ensure_ascii=False), overwrite=True
        )


def _suffix(figure: str) -> str:
    """A stored figure's file type: a PNG, or the mode viewer's data (``viewer``) as JSON."""
    return ".json" if figure == "viewer" else ".png"
