#!/usr/bin/env python3
"""Writes _hamal.pyi, the type stubs of the compiled module (PEP 561), from
the module itself: mypy's stubgen (python3-mypy) reads the signatures
pybind11 puts in the docstrings. Run by python/CMakeLists.txt after each
build of the module:

    generate_stubs.py <dir holding the built package hamal/> <output .pyi>

stubgen copies pybind11's spellings that are not Python types; these fix-ups
make the stub one that mypy checks without an error:
- `numpy.ndarray[numpy.float64[3,1]]` (an Eigen matrix) and
  `numpy.ndarray[numpy.uint64]` become `numpy.typing.NDArray[<dtype>]`;
- `handle` (pybind11's untyped argument) becomes `Any`;
- a typed `__eq__`/`__ne__` and `__hash__ = None` (a class with `__eq__`)
  get typeshed's `# type: ignore`;
- the typing names used but not imported (`Set`) are imported.
"""

import os
import re
import sys
import tempfile

# The typing names pybind11's signatures use.
TYPING_NAMES = ("Any", "Callable", "ClassVar", "Dict", "Iterable", "Iterator", "List", "Optional",
                "Sequence", "Set", "Tuple", "Union")


def fix_up(text):
    text = re.sub(r"numpy\.ndarray\[(numpy\.\w+)(\[[^\]]*\])?\]", r"numpy.typing.NDArray[\1]", text)
    text = re.sub(r"(?<=[:>\[,] )handle\b|(?<=\[)handle\b", "Any", text)
    if "numpy.typing." in text:
        text = re.sub(r"^import numpy$", "import numpy\nimport numpy.typing", text, count=1, flags=re.M)
    # What typeshed does for a typed __eq__ and an unhashable class.
    text = re.sub(r"^(\s+def __(?:eq|ne)__\(self, \w+: (?!object\))\w+\) -> bool: \.\.\.)$",
                  r"\1  # type: ignore[override]", text, flags=re.M)
    text = re.sub(r"^(\s+__hash__: ClassVar\[None\] = \.\.\.)$", r"\1  # type: ignore[assignment]",
                  text, flags=re.M)
    imported = set()
    for names in re.findall(r"^from typing import (.*)\n", text, flags=re.M):
        imported.update(name.strip() for name in names.split(","))
    text = re.sub(r"^from typing import .*\n", "", text, flags=re.M)
    imported.update(name for name in TYPING_NAMES if re.search(rf"(?<![\w.]){name}\b", text))
    return ("# Generated from the built module by python/generate_stubs.py (mypy's stubgen).\n"
            f"from typing import {', '.join(sorted(imported))}\n" + text.lstrip("\n"))


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    package_parent, output = sys.argv[1:]
    sys.path.insert(0, os.path.abspath(package_parent))
    from mypy.stubgen import main as stubgen  # Debian's mypy is compiled: no `-m mypy.stubgen`
    with tempfile.TemporaryDirectory() as tmp:
        stubgen(["-m", "hamal._hamal", "-o", tmp, "--quiet"])
        with open(os.path.join(tmp, "hamal", "_hamal.pyi")) as f:
            text = fix_up(f.read())
    with open(output + ".tmp", "w") as f:
        f.write(text)
    os.replace(output + ".tmp", output)


if __name__ == "__main__":
    main()
