"""A JSON file written whole or not at all, as core/output_file.h writes the
C++ tools' outputs: the value goes to a temporary of a unique name in the same
directory, renamed over the path at the end; a failed write leaves the old
file as it was and no temporary behind."""

import json
import os
import tempfile


def write_json(path, value, indent=1):
    directory = os.path.dirname(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(prefix=os.path.basename(path) + ".tmp.", dir=directory)
    try:
        with os.fdopen(fd, "w") as f:
            json.dump(value, f, indent=indent)
        os.replace(tmp, path)
    except BaseException:
        try:
            os.remove(tmp)
        except FileNotFoundError:
            pass
        raise
