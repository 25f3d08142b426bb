#!/usr/bin/env python3
"""Lists the C++ structs and classes with more than a limit (12 by default)
of public mutable data members, the widest first, so they can be grouped
(CONTRIBUTING.md, "House rules": an options or result aggregate groups its
fields by what they are about, as Ceres' Solver::Options does not and
GTSAM's ISAM2Params' sub-structs do).

A brace-counting pass like scripts/long_functions.py, not a parser: at a
struct's or class's own scope every statement ending in ';' is a member;
it is a public mutable data member when it is under `public:` (a struct's
default), has no parameter list before its initialiser, and is not
`static`, `const`, `constexpr`, `using`, `typedef`, `friend` or a nested
type. Members of nested types count for the nested type. Tests (tests/,
*_test.cc) are left out unless --tests.

    scripts/wide_structs.py [--limit 12] [--tests] [folders...]

Exits 1 when it lists any.
"""
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from long_functions import blank, list_offenders  # noqa: E402

TYPE_HEAD = re.compile(r"(?:^|[\s;}>])(struct|class|union)\s+(?:alignas\s*\([^)]*\)\s*)?(\w+)[^;()]*$", re.S)
NOT_DATA = re.compile(r"^\s*(?:static|const|constexpr|using|typedef|friend|enum|struct|class|union|template|virtual|explicit|operator|~)\b")
ACCESS = re.compile(r"\b(public|private|protected)\s*:(?!:)")


def is_data(statement):
    """True when a member statement declares mutable data."""
    s = " ".join(statement.split())
    if not s or NOT_DATA.search(s):
        return False
    # A parameter list before any initialiser makes a function.
    cut = len(s)
    for mark in ("=", "{"):
        k = s.find(mark)
        if k >= 0:
            cut = min(cut, k)
    return "(" not in s[:cut]


def declarators(statement):
    """How many mutable data members a member statement declares: `int a,
    b;` two, `double x = 0.1, y = 0.2;` two, `T x{1, 2};` one, `enum class
    E {...} e = ...;` one, a function, type or constant none."""
    s = " ".join(statement.split())
    enum = re.match(r"^\s*enum\b[^{]*\{[^}]*\}\s*(.*)$", s)
    if enum:
        s = enum.group(1)
        if not s.strip():
            return 0
    elif not is_data(s):
        return 0
    count, depth, angle = 1, 0, 0
    initialising = False
    for c in s:
        if c in "([{":
            depth += 1
        elif c in ")]}":
            depth -= 1
        elif c == "=" and depth == 0:
            initialising = True
        elif c == "<" and depth == 0 and not initialising:
            angle += 1
        elif c == ">" and depth == 0 and not initialising and angle:
            angle -= 1
        elif c == "," and depth == 0 and angle == 0:
            count += 1
            initialising = False
    return count


def structs(path):
    """(line, name, count) of every struct or class in `path`."""
    with open(path, encoding="utf-8", errors="replace") as f:
        text = blank(f.read())
    text = re.sub(r"(?m)^\s*#.*(?:\\\n.*)*$", lambda m: re.sub(r"[^\n]", " ", m.group(0)), text)
    found = []
    # Per open brace: None for a non-type scope, else [name, line, public, count].
    stack = []
    start = 0
    depth_skip = 0  # braces inside a member's initialiser or a function body

    def scope():
        return stack[-1] if stack else None

    i, n = 0, len(text)
    while i < n:
        c = text[i]
        top = scope()
        if c == "{":
            header = text[start:i]
            m = TYPE_HEAD.search(header)
            if m and not re.search(r"\benum\b", header):
                kind, name = m.group(1), m.group(2)
                line = text.count("\n", 0, start + len(header) - len(header.lstrip())) + 1
                stack.append([name, line, kind != "class", 0])
                start = i + 1
            elif top is not None and top[0] is not None and not re.search(r"\)\s*(?:const\s*)?(?:noexcept\s*)?(?:override\s*)?(?:final\s*)?(?:->[^{]*)?$|\b(?:namespace|extern)\b", header) \
                    and header.strip():
                # A member's brace initialiser: skip to its closing brace;
                # the statement ends at the ';' after it.
                d = 1
                j = i + 1
                while j < n and d:
                    d += {"{": 1, "}": -1}.get(text[j], 0)
                    j += 1
                i = j
                continue
            else:
                stack.append([None])
                start = i + 1
        elif c == "}":
            if stack:
                closed = stack.pop()
                if closed[0] is not None:
                    found.append((closed[1], closed[0], closed[3]))
                    # `struct X {...} x;` declares no member of the outer
                    # type here: its trailing declarator is rare enough.
            start = i + 1
        elif c == ";":
            if top is not None and top[0] is not None:
                statement = text[start:i]
                # Access specifiers inside the statement's text come first.
                for a in ACCESS.finditer(statement):
                    top[2] = a.group(1) == "public"
                tail = ACCESS.split(statement)[-1] if ACCESS.search(statement) else statement
                if top[2]:
                    top[3] += declarators(tail)
            start = i + 1
        elif c == ":" and top is not None and top[0] is not None:
            # An access specifier ends a header; `a::b` is not one.
            m = ACCESS.search(text, start, i + 2)
            if m and m.end() == i + 1:
                top[2] = m.group(1) == "public"
                start = i + 1
        i += 1
    return found


def main():
    return list_offenders(
        __doc__, 12,
        lambda path: [(count, line, struct) for line, struct, count in structs(path)],
        "struct(s) with over {limit} public mutable fields")


if __name__ == "__main__":
    sys.exit(main())
