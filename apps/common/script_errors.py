"""One-line errors for the Python runners and report scripts, as the C++
tools give them (apps/common/cli.h runMain): a folder that cannot be written
(read-only, full disk, a missing directory), a file that cannot be read, or a
hamal tool that failed ends the program with "program: error: PATH: reason"
on stderr and exit status 1, never a traceback. The tool's own message is
already on stderr when a tool failed.

    if __name__ == "__main__":
        sys.exit(script_errors.run("hamal_sweep", main))

Standard library only, as the runners are.
"""

import subprocess
import sys


def message(program, error):
    """The one line an error becomes."""
    if isinstance(error, subprocess.CalledProcessError):
        command = error.cmd if isinstance(error.cmd, str) else " ".join(map(str, error.cmd))
        return f"{program}: error: {command}: exited with status {error.returncode}"
    where = error.filename if getattr(error, "filename", None) is not None else None
    reason = getattr(error, "strerror", None) or str(error) or type(error).__name__
    if where is not None and getattr(error, "filename2", None) is not None:
        where = f"{where} -> {error.filename2}"
    return f"{program}: error: {where}: {reason}" if where is not None else \
        f"{program}: error: {reason}"


def run(program, main, *args):
    """main(*args)'s exit status; an OSError or a failed tool is one line and 1."""
    try:
        return main(*args)
    except (OSError, subprocess.CalledProcessError) as e:
        try:
            sys.stdout.flush()
        except OSError:
            pass
        print(message(program, e), file=sys.stderr)
        return 1
