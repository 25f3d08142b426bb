"""Where the public datasets are: HAMAL_DATA_DIR, else, for the package in a
CMake build tree (build/python/hamal), the data directory that tree's C++
tests read (its HAMAL_DATA_DIR cache entry, ../shared/data beside the
checkout by default). An installed package (pip, cmake --install) has no
checkout to look beside: it needs HAMAL_DATA_DIR. The datasets are not
shipped; third_party_notes/datasets.md in hamal's repository says where each
comes from."""

import os
import re

from ._hamal import Error

# build/python/hamal -> build/, whose CMakeCache.txt names the data and source.
_BUILD_DIR = os.path.dirname(os.path.dirname(os.path.dirname(os.path.realpath(__file__))))


def _build_tree_data_dir():
    try:
        with open(os.path.join(_BUILD_DIR, "CMakeCache.txt")) as f:
            cache = f.read()
    except OSError:
        return None
    data = re.search(r"^HAMAL_DATA_DIR:PATH=(.+)$", cache, flags=re.M)
    if data:
        return os.path.normpath(data.group(1))
    source = re.search(r"^hamal_SOURCE_DIR:STATIC=(.+)$", cache, flags=re.M)
    if source:
        return os.path.normpath(os.path.join(source.group(1), "..", "shared", "data"))
    return None


def data_dir():
    """The dataset directory: $HAMAL_DATA_DIR, else the build tree's (see the
    module's docstring); hamal.Error for an installed package without
    HAMAL_DATA_DIR."""
    env = os.environ.get("HAMAL_DATA_DIR")
    if env:
        return env
    found = _build_tree_data_dir()
    if found:
        return found
    raise Error(f"no dataset directory: HAMAL_DATA_DIR is not set, and hamal is installed "
                f"({os.path.dirname(os.path.realpath(__file__))}), not in a build tree; set "
                "HAMAL_DATA_DIR to the directory of the public datasets "
                "(third_party_notes/datasets.md in hamal's repository says where each comes from)")


def dataset(name):
    """The path of dataset `name` ("M3500.toro"); hamal.Error when it is missing."""
    directory = data_dir()
    path = os.path.join(directory, name)
    if not os.path.isfile(path):
        source = ("HAMAL_DATA_DIR" if os.environ.get("HAMAL_DATA_DIR")
                  else "the build tree's; HAMAL_DATA_DIR names another")
        raise Error(f"dataset {name} not found in {directory} ({source}); "
                    "third_party_notes/datasets.md in hamal's repository says where each comes from")
    return path
