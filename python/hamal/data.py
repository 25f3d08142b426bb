"""Where the public datasets are: HAMAL_DATA_DIR, else ../shared/data beside
the checkout (the rule of the C++ tests and scripts; the datasets are not
shipped, third_party_notes/datasets.md says where each comes from)."""

import os

from ._hamal import Error

_SOURCE_DIR = os.path.dirname(os.path.dirname(os.path.dirname(os.path.realpath(__file__))))


def data_dir():
    """The dataset directory: $HAMAL_DATA_DIR, else ../shared/data beside the
    checkout this package was built from (or the current directory's)."""
    env = os.environ.get("HAMAL_DATA_DIR")
    if env:
        return env
    for root in (_SOURCE_DIR, os.getcwd()):
        # build/python/hamal -> the build tree's parent; python/hamal -> the checkout.
        for up in (root, os.path.dirname(root)):
            candidate = os.path.join(up, "..", "shared", "data")
            if os.path.isdir(candidate):
                return os.path.normpath(candidate)
    return os.path.normpath(os.path.join(os.getcwd(), "..", "shared", "data"))


def dataset(name):
    """The path of dataset `name` ("M3500.toro"); hamal.Error when it is missing."""
    path = os.path.join(data_dir(), name)
    if not os.path.isfile(path):
        raise Error(f"dataset {name} not found in {data_dir()} (set HAMAL_DATA_DIR; "
                    "third_party_notes/datasets.md says where each comes from)")
    return path
