"""Writing results: whole output directories appear at once, or not at all."""

from __future__ import annotations

import json
import os
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from .errors import WetclutchError


def check_target(target: str | Path, option: str = "--out") -> Path:
    """``target`` as a path an output may replace, or a one-line error naming ``option``.

    Replacing an output renames the old one away, which a directory that holds the
    current working directory (or is it) cannot be; an empty path would name that
    directory too.

    Parameters
    ----------
    target
        The output's path as given.
    option
        The option that gave it, named in the error.

    Returns
    -------
    Path
        ``target`` as a path.

    Raises
    ------
    WetclutchError
        ``target`` is empty, or is or contains the current working directory.
    """
    if not str(target).strip():
        raise WetclutchError(f"{option} must not be empty")
    path = Path(target)
    resolved, cwd = path.resolve(), Path.cwd().resolve()
    if resolved == cwd or resolved in cwd.parents:
        raise WetclutchError(f"{option} '{target}' is or contains the current directory, which cannot be replaced")
    return path


def check_out_dir(target: str | Path, option: str = "--out") -> Path:
    """``target`` as an output directory that can be written, or a one-line error naming ``option``: what
    :func:`check_target` refuses, and an existing file in its place or on its way (a file cannot become a
    directory) or a place where no directory can be made (no permission, a read-only file system). Checked before
    any work, so that minutes of launches do not end in it.

    Raises
    ------
    WetclutchError
        ``target`` cannot be an output directory.
    """
    path = check_target(target, option)
    if path.exists() and not path.is_dir():
        raise WetclutchError(f"{option} '{target}' is a file, not a directory")
    # the nearest existing directory above it: where the temporary directory (or its parents) will be made
    base = path.parent if str(path.parent) else Path(".")
    while not base.exists() and base != base.parent:
        base = base.parent
    if not base.is_dir():
        raise WetclutchError(f"{option} '{target}': '{base}' is a file, not a directory")
    try:
        Path(tempfile.mkdtemp(prefix=f".{path.name}.", suffix=".probe", dir=base)).rmdir()
    except OSError as err:
        raise WetclutchError(f"{option} '{target}': cannot create a directory in '{base}': "
                             f"{err.strerror or err}") from None
    return path


def _umask() -> int:
    """The process's file-mode creation mask: from ``/proc`` where it is there, else read by setting it and putting it
    back (a moment in which another thread's new file would take 022)."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


@contextmanager
def atomic_dir(target: str | Path) -> Iterator[Path]:
    """Yield a temporary directory that replaces ``target`` only if the block succeeds.

    The temporary directory sits beside ``target`` (same file system), so the
    final step is a rename; on any error it is removed and ``target`` is left as
    it was.

    Parameters
    ----------
    target
        The output directory (see :func:`check_target`).

    Yields
    ------
    Path
        The temporary directory to write the output into.

    Raises
    ------
    WetclutchError
        ``target`` cannot be replaced, or the output cannot be written.
    """
    target = check_target(target)
    parent = target.parent if str(target.parent) else Path(".")
    try:
        parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=f".{target.name}.", suffix=".tmp", dir=parent))
    except OSError as err:
        raise WetclutchError(f"cannot create output directory '{target}': {err.strerror}") from None
    old: Path | None = None
    try:
        yield tmp
        # a temporary directory is private (0700); the output is made as any directory would be (the umask's mode)
        os.chmod(tmp, 0o777 & ~_umask())
        if target.is_file():
            raise WetclutchError(f"output path '{target}' is a file, not a directory")
        if target.exists():
            old = Path(tempfile.mkdtemp(prefix=f".{target.name}.", suffix=".old", dir=parent))
            os.rename(target, old / "d")
        try:
            os.rename(tmp, target)
        except OSError:
            if old is not None and (old / "d").exists():
                os.rename(old / "d", target)
            raise
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
            old = None
    except OSError as err:
        shutil.rmtree(tmp, ignore_errors=True)
        _put_back(old, target)
        raise WetclutchError(f"cannot write output '{target}': {err.strerror or err}") from None
    except BaseException:
        # an interrupt (Ctrl-C, SIGTERM) between the two renames must not leave the previous output hidden away
        shutil.rmtree(tmp, ignore_errors=True)
        _put_back(old, target)
        raise
    finally:
        # the previous output, if it could not be put back, stays rather than being lost
        if old is not None and not (old / "d").exists():
            shutil.rmtree(old, ignore_errors=True)


def _put_back(old: Path | None, target: Path) -> None:
    """Put the previous output (renamed to ``old / "d"``) back at ``target`` if the new one did not take its place."""
    if old is not None and (old / "d").exists() and not target.exists():
        try:
            os.rename(old / "d", target)
        except OSError:
            pass  # it stays in ``old`` rather than being lost


def _jsonable(v: Any) -> Any:
    if isinstance(v, dict):
        return {k: _jsonable(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_jsonable(x) for x in v]
    if isinstance(v, np.generic):
        return v.item()
    if isinstance(v, float) and not np.isfinite(v):
        return None
    return v


def write_csv(frame: Any, path: Path, digits: int = 10) -> None:
    """Write a numeric ``frame`` (pandas DataFrame) as CSV with ``digits`` significant digits, as
    ``frame.to_csv(path, index=False, float_format=f"%.{digits}g")`` does, in a quarter of its time: one format
    string per row, not one call per value (a rig run's 1 M rows of true states: 16 s through pandas, 4 s here).
    A frame with missing values goes through pandas, which leaves their cells empty."""
    values = frame.to_numpy(dtype=np.float64)
    if np.isnan(values).any():
        frame.to_csv(path, index=False, float_format=f"%.{digits}g")
        return
    np.savetxt(path, values, fmt=f"%.{digits}g", delimiter=",", header=",".join(map(str, frame.columns)),
               comments="")


def write_json(path: Path, data: dict[str, Any]) -> None:
    path.write_text(json.dumps(_jsonable(data), indent=2) + "\n")
