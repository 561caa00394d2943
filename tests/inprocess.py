"""``wetclutch`` commands run in the test's own process, through what the console script runs."""

from __future__ import annotations

import io
import subprocess
import warnings
from collections.abc import Sequence
from contextlib import chdir, redirect_stderr, redirect_stdout
from pathlib import Path

from wetclutch import cli

#: the warning categories a plain ``python`` process does not show (pytest's filters would record every warning
#: instead of showing it)
_PYTHON_IGNORES = (DeprecationWarning, PendingDeprecationWarning, ImportWarning, ResourceWarning)


def invoke(args: Sequence[str], cwd: Path | None = None) -> subprocess.CompletedProcess:
    """``wetclutch ARGS`` in this process through :func:`wetclutch.cli.main`: its exit status, standard output and
    standard error, with the warnings a plain ``python`` shows written to standard error as it writes them. The same
    code path as a new process without a new interpreter's start and its loading of the compiled code (some 3 s a
    command); tests that need the process itself (``python -m wetclutch``, signals) start one."""
    out, err = io.StringIO(), io.StringIO()
    with (warnings.catch_warnings(record=True) as seen, redirect_stdout(out), redirect_stderr(err),
          chdir(cwd if cwd is not None else Path.cwd())):
        warnings.resetwarnings()
        warnings.simplefilter("default")
        for category in _PYTHON_IGNORES:
            warnings.simplefilter("ignore", category)
        try:
            code = cli.main(list(args))
        except SystemExit as stop:  # argparse's usage errors and --help
            code = stop.code if isinstance(stop.code, int) else (0 if stop.code is None else 1)
    shown = "".join(warnings.formatwarning(w.message, w.category, w.filename, w.lineno, w.line) for w in seen)
    return subprocess.CompletedProcess(["wetclutch", *args], code, out.getvalue(), err.getvalue() + shown)
