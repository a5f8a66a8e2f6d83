"""Study storage: the design, every output as it finishes, and resume.

An HDF5 study file holds the definition (JSON attribute), the design ``X``
``(R * M, D)``, the outputs ``Y``, the input fingerprints ``key`` and a ``status``
per row (0 pending, 1 done, 2 failed), rows numbered replicate-major
(`hdsim.sensitivity.design`).

Crash safety without SWMR: every dataset is contiguous and fully written when the
file is created (built under a temporary name, then renamed), so evaluating only
overwrites raw bytes at fixed offsets — no HDF5 metadata changes that a SIGKILL
could tear. Each chunk writes ``Y`` and ``key``, flushes, then writes ``status`` and
flushes: a row marked done always has its output on disk. Metadata (failure
messages, a bigger N) changes only at quiet points, and growing N rewrites the file
atomically.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from hdsim.atomic import atomic_path
from hdsim.errors import InputError
from hdsim.sensitivity.layout import PIECE, Layout, runs
from hdsim.sensitivity.problem import PYTHON_WORDING, Wording

FORMAT, VERSION = "hdsim-sobol-study", 1
PENDING, DONE, FAILED = 0, 1, 2
INTERRUPTED = "failure message not saved (the run was interrupted)"


class MemoryStore(Layout):
    """A study kept in memory (no ``--out``); same interface as `H5Store`."""

    path = None
    dirty = False  # failure messages changed since the last save

    def __init__(self, definition: dict, n: int):
        super().__init__(definition, n)
        self.data = _empty_arrays(self.shape)
        for g0, X in self.pieces():
            self.data["X"][g0:g0 + len(X)] = X
        self.messages: dict[int, str] = {}

    # --- access -----------------------------------------------------------------------
    def read(self, name: str, rows: np.ndarray) -> np.ndarray:
        ds = self.data[name]
        return np.concatenate([ds[a:b] for a, b in runs(rows)]) if len(rows) else ds[:0]

    def reader(self, rows: np.ndarray) -> "RowReader":
        """Design rows ``rows`` as a lazy array-like (read a slice at a time)."""
        return RowReader(self, np.asarray(rows))

    def blocks(self, n: int):
        """Yield ``(rows, X, Y, key, status)`` for the first ``n`` base points, at most
        PIECE blocks at a time, never crossing a replicate."""
        R, k = self.replicates, self.k
        per = self.prefix_rows(n).reshape(R, -1)
        for r in range(R):
            for a in range(0, per.shape[1], PIECE * k):
                rows = per[r, a:a + PIECE * k]
                yield rows, *(self.read(name, rows) for name in ("X", "Y", "key", "status"))

    def pending(self, n: int, retry_failed: bool = False) -> np.ndarray:
        rows = self.prefix_rows(n)
        status = self.read("status", rows)
        todo = (status == PENDING) | ((status == FAILED) if retry_failed else False)
        return rows[todo]

    def write(self, rows, y, key, errors) -> None:
        """Store one finished chunk (``errors``: local position -> message)."""
        status = np.full(len(rows), DONE, np.int8)
        for g in rows:  # a retried row that now succeeds loses its old message
            self.dirty |= self.messages.pop(int(g), None) is not None
        for i, msg in errors.items():
            status[i] = FAILED
            self.messages[int(rows[i])] = msg
            self.dirty = True
        for a, b, off in runs(rows, offsets=True):
            self.data["Y"][a:b] = y[off:off + b - a]
            self.data["key"][a:b] = key[off:off + b - a]
        self._flush()
        for a, b, off in runs(rows, offsets=True):
            self.data["status"][a:b] = status[off:off + b - a]
        self._flush()

    def failures(self, n: int) -> dict[int, str]:
        """Row -> message for failed rows within the first ``n`` base points."""
        rows = self.prefix_rows(n)
        failed = rows[self.read("status", rows) == FAILED]
        return {int(g): self.messages.get(int(g), INTERRUPTED) for g in failed}

    def counts(self, n: int | None = None) -> dict[str, int]:
        status = self.read("status", self.prefix_rows(n or self.n))
        return {"done": int((status == DONE).sum()), "failed": int((status == FAILED).sum()),
                "pending": int((status == PENDING).sum())}

    def save_failures(self) -> None:
        pass

    def _flush(self) -> None:
        pass

    def close(self) -> None:
        pass


class H5Store(MemoryStore):
    """A study in an HDF5 file; open with `open_store`."""

    def __init__(self, path: Path):
        import h5py

        self.path = Path(path)
        try:
            self.file = h5py.File(self.path, "r+")
        except BlockingIOError:
            raise InputError(f"{self.path} is open in another process") from None
        except OSError as exc:
            raise InputError(f"cannot open study {self.path}: {exc}") from None
        attrs = self.file.attrs
        if attrs.get("format") != FORMAT:
            self.file.close()
            raise InputError(f"{self.path} is not an hdsim Sobol study file")
        try:
            self.definition = json.loads(attrs["definition"])
            self.n = int(attrs["n"])
            self.data = {name: self.file[name] for name in ("X", "Y", "key", "status")}
            self.messages = _read_messages(self.file)
        except (KeyError, ValueError, TypeError) as exc:  # a file edited or cut by hand: the input, not the program
            self.file.close()
            raise InputError(f"{self.path} is a damaged study file ({type(exc).__name__}: {exc}); "
                             "start the study again with another --out") from None

    def save_failures(self) -> None:
        """Write failure messages if they changed (quiet point: no chunk in flight)."""
        if self.dirty and self.file.id.valid:
            _write_messages(self.file, self.messages)
            self.file.flush()
            self.dirty = False

    def _flush(self) -> None:
        self.file.flush()

    def close(self) -> None:
        if self.file.id.valid:
            self.file.close()


class RowReader:
    """Lazy view of some design rows of a store: ``len()`` and slicing only."""

    def __init__(self, store, rows):
        self.store, self.rows = store, rows

    def __len__(self) -> int:
        return len(self.rows)

    def __getitem__(self, sl) -> np.ndarray:
        return self.store.read("X", self.rows[sl])


def open_store(definition: dict, n: int, path=None, resume=False, wording: Wording = PYTHON_WORDING):
    """Create, reopen or extend the study for ``definition`` with ``n`` base points.

    Parameters
    ----------
    definition : dict
        Problem, seed, second order, replicates and model of the study.
    n : int
        Base points N.
    path : str or os.PathLike, optional
        Study file; None keeps the study in memory.
    resume : bool
        Continue an existing file (extended when ``n`` is larger than its N).
    wording : Wording
        How the messages name ``out`` and ``resume`` (`CLI_WORDING`: ``--out``, ``--resume``).

    Returns
    -------
    MemoryStore or H5Store
        The open store.

    Raises
    ------
    InputError
        If ``resume`` is given without ``path``, ``path`` exists without ``resume``,
        holds a study with a different
        definition, or is open in another process.
    """
    if path is None:
        if resume:  # nothing to continue: a study in memory is lost with its process
            raise InputError(f"{wording.resume} needs {wording.out}: the study file to continue")
        return MemoryStore(definition, n)
    path = Path(path)
    if not path.exists():
        _create(path, Layout(definition, n))
        return H5Store(path)
    if not resume:
        raise InputError(f"{path} exists; pass {wording.resume} to continue it, or choose another {wording.out}")
    store = H5Store(path)
    diff = _differences(store.definition, definition)
    if diff:
        store.close()
        raise InputError(f"{path} holds a different study ({'; '.join(diff)}); "
                         f"choose another {wording.out}")
    if n > store.n:
        store.close()
        _extend(path, n)
        store = H5Store(path)
    return store


def _create(path: Path, geo: Layout, copy_from: H5Store | None = None) -> None:
    import h5py

    with atomic_path(path) as tmp:
        with h5py.File(tmp, "w") as f:
            f.attrs.update({"format": FORMAT, "version": VERSION, "n": geo.n,
                            "definition": json.dumps(geo.definition, sort_keys=True)})
            rows, D = geo.shape
            for name, arr in _empty_arrays((0, D)).items():
                f.create_dataset(name, shape=(rows,) + arr.shape[1:], dtype=arr.dtype,
                                 track_times=False)
            for g0, X in geo.pieces():
                _fill_piece(f, geo, g0, X, copy_from)
            if copy_from is not None:
                _write_messages(f, {copy_from.regrid(g, geo): m
                                    for g, m in copy_from.messages.items()})


def _fill_piece(f, geo, g0, X, old):
    """Write one piece of design; carry over outputs of an older, smaller study."""
    g1 = g0 + len(X)
    Y, key, status = (np.full(len(X), np.nan), np.zeros(len(X), np.uint64),
                      np.zeros(len(X), np.int8))
    if old is not None:
        r, j0 = divmod(g0, geo.rows_per_replicate)
        m = max(0, min(len(X), old.rows_per_replicate - j0))  # rows the old study has
        if m:
            o0 = r * old.rows_per_replicate + j0
            if not np.array_equal(old.data["X"][o0:o0 + m], X[:m]):
                raise InputError("the stored design is not the start of the bigger one "
                                 "(SALib or scipy changed?); start a new study file")
            Y[:m], key[:m] = old.data["Y"][o0:o0 + m], old.data["key"][o0:o0 + m]
            status[:m] = old.data["status"][o0:o0 + m]
    f["X"][g0:g1], f["Y"][g0:g1], f["key"][g0:g1], f["status"][g0:g1] = X, Y, key, status


def _extend(path: Path, n: int) -> None:
    old = H5Store(path)
    try:
        _create(path, Layout(old.definition, n), copy_from=old)
    finally:
        old.close()


def _empty_arrays(shape):
    n = shape[0]
    return {"X": np.zeros((n, shape[1])), "Y": np.full(n, np.nan),
            "key": np.zeros(n, np.uint64), "status": np.zeros(n, np.int8)}


def _read_messages(f) -> dict[int, str]:
    if "failures" not in f:
        return {}
    rows, msgs = f["failures/row"][()], f["failures/message"].asstr()[()]
    return {int(r): str(m) for r, m in zip(rows, msgs)}


def _write_messages(f, messages: dict[int, str]) -> None:
    import h5py

    if "failures" in f:
        del f["failures"]
    g = f.create_group("failures")
    rows = sorted(messages)
    g.create_dataset("row", data=np.asarray(rows, dtype=np.int64))
    g.create_dataset("message", data=[messages[r] for r in rows], dtype=h5py.string_dtype())


def _differences(stored: dict, wanted: dict) -> list[str]:
    """What differs between two definitions (compared after a JSON round trip)."""
    stored, wanted = json.loads(json.dumps(stored)), json.loads(json.dumps(wanted))
    return [f"{k}: stored {json.dumps(stored.get(k))}, asked {json.dumps(wanted.get(k))}"
            for k in sorted(set(stored) | set(wanted)) if stored.get(k) != wanted.get(k)]
