"""Write files atomically: to a temporary file beside the target, then rename.

A reader never sees a half-written result, and a crash leaves the old file (or
none) in place. Inside `atomic_group` the renames wait for the end of the block, so the
files of one result (a run's HDF5 file and its figures) appear together or not at all.
"""

from __future__ import annotations

import contextlib
import contextvars
import errno
import glob
import io
import os
import tempfile
from pathlib import Path


#: the (temporary, target) renames an `atomic_group` holds back, or None outside one
_PENDING: contextvars.ContextVar[list | None] = contextvars.ContextVar("hdsim_atomic_group", default=None)


@contextlib.contextmanager
def atomic_group():
    """Files written with `atomic_path` inside the block replace their targets together
    when it ends; if it raises, none does and the temporary files are removed.

    A full disk while the third figure of a run is saved then leaves the folder as it was,
    not a new result file beside the old figures.
    """
    pending: list = []
    token = _PENDING.set(pending)
    try:
        yield
    except BaseException:
        for tmp, _ in pending:
            with contextlib.suppress(FileNotFoundError):
                os.unlink(tmp)
        raise
    finally:
        _PENDING.reset(token)
    for tmp, target in pending:
        os.replace(tmp, target)


@contextlib.contextmanager
def atomic_path(target: str | os.PathLike):
    """Yield a temporary path beside ``target``; rename it over ``target`` on success.

    The temporary file gets the mode an ordinary new file would get (umask applied);
    on an exception it is removed and ``target`` is left untouched.

    Parameters
    ----------
    target : str or os.PathLike
        The file to write; missing folders are created.

    Yields
    ------
    pathlib.Path
        The temporary file to write to.
    """
    target = Path(target)
    if is_special_file(target):
        # the rename would put a file where a device or pipe was (/dev/null, as root)
        raise OSError(errno.EINVAL, "not a regular file (a device, pipe or socket): a result is not written "
                      "over it", str(target))
    target.parent.mkdir(parents=True, exist_ok=True)
    _remove_orphans(target)
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.{os.getpid()}.", suffix=".tmp", dir=target.parent)
    os.close(fd)
    # mkstemp creates 0600; give the result the mode an ordinary file would get
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)
    try:
        yield Path(tmp)
        group = _PENDING.get()
        if group is None:
            os.replace(tmp, target)
        else:  # the group renames it with the others when it ends
            group.append((tmp, target))
    except BaseException as exc:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        if isinstance(exc, OSError) and exc.errno is not None and exc.filename is None:
            # a write that failed (a full disk) names no file: the message names the result's
            raise OSError(exc.errno, exc.strerror or str(exc), str(target)) from exc
        raise


def is_special_file(path: Path) -> bool:
    """Whether ``path`` is a device, a pipe or a socket (``/dev/null``): a result written beside
    it and renamed over it would replace it with a regular file."""
    return path.exists() and not path.is_file() and not path.is_dir()


def _remove_orphans(target: Path) -> None:
    """Remove temporary files of ``target`` left by a process of this machine that is gone.

    A process killed outright (SIGKILL, the OOM killer) cannot remove its temporary file,
    and a study's can be as large as the study. The writer's pid is in the name; a file
    whose writer still runs, or whose name holds none, is left alone. (The pid is this
    machine's: two machines writing one result into a shared folder race anyway.)
    """
    for orphan in target.parent.glob(f".{glob.escape(target.name)}.*.tmp"):
        pid = orphan.name[len(target.name) + 2:].split(".", 1)[0]
        if pid.isdigit() and not _running(int(pid)):
            with contextlib.suppress(OSError):
                orphan.unlink()


def _running(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # another user's process: it runs
        return True
    return True


def write_text_atomic(target: str | os.PathLike, text: str) -> None:
    """Write text to a file atomically.

    Parameters
    ----------
    target : str or os.PathLike
        The file to write; missing folders are created.
    text : str
        The content, written in the platform's default encoding.
    """
    with atomic_path(target) as tmp:
        tmp.write_text(text)


@contextlib.contextmanager
def hdf5_atomic(target: str | os.PathLike):
    """Yield an ``h5py.File`` made in memory; when the block ends its bytes are written to
    ``target`` atomically (`atomic_path`), and nothing is written if the block raises.

    The HDF5 library then never writes to the disk itself: on a full disk its C-level
    write errors crashed the process (a segmentation fault after hundreds of lines of
    HDF5 diagnostics); here the write fails in Python, with its errno and the path.
    A result file is a few megabytes, so holding it in memory costs nothing.
    """
    import h5py

    buffer = io.BytesIO()
    with h5py.File(buffer, "w") as handle:
        yield handle
    with atomic_path(target) as tmp:
        tmp.write_bytes(buffer.getbuffer())


def check_writable_folder(folder: str | os.PathLike) -> Path:
    """Make sure results can be written into ``folder`` before any work is done.

    Nothing is left behind: a temporary file is created and removed in the folder, or, when
    it does not exist yet, in its nearest existing parent (which must be a folder the
    results can be created in); the folder itself is made only when results are written.

    Raises
    ------
    hdsim.errors.InputError
        One line naming the folder and the cause (read-only, no permission, not a folder,
        full disk): an environment the user must fix, not a failure of the program.
    """
    from hdsim.errors import InputError

    folder = Path(folder)
    probe = folder
    while not probe.exists() and probe != probe.parent:
        probe = probe.parent
    try:
        if not probe.is_dir():
            raise NotADirectoryError(20, "not a folder", str(probe))
        fd, tmp = tempfile.mkstemp(prefix=".hdsim-write-check.", dir=probe)
        os.close(fd)
        os.unlink(tmp)
    except OSError as exc:
        raise InputError(f"cannot write into {folder}: {exc.strerror or exc}") from None
    return folder
