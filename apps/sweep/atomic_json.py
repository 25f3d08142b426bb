"""A results file written whole or not at all, as core/output_file.h writes the
C++ tools' outputs: the content goes to a temporary of a unique name in the
same directory, renamed over the path at the end; a failed write leaves the
old file as it was and no temporary behind."""

import json
import os
import tempfile


def write_atomically(path, write, newline=None):
    """Calls write(f) on a text file that becomes `path` when it returns."""
    directory = os.path.dirname(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(prefix=os.path.basename(path) + ".tmp.", dir=directory)
    try:
        with os.fdopen(fd, "w", newline=newline) as f:
            write(f)
        os.replace(tmp, path)
    except BaseException:
        try:
            os.remove(tmp)
        except FileNotFoundError:
            pass
        raise


def write_json(path, value, indent=1):
    write_atomically(path, lambda f: json.dump(value, f, indent=indent))
