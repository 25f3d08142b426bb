#!/usr/bin/env python3
"""Lists the C++ functions longer than a limit (150 lines by default), the
longest first, so the worst can be split (CONTRIBUTING.md, "House rules":
one idea per file, and per function).

A brace-counting pass, not a parser: comments, string and character
literals are blanked, then every '{' opened at namespace or class scope
whose header (the text since the previous ';', '{' or '}') has a parameter
list and is not a control statement, a type or an initialiser is a function
body; lambdas and local classes count in their enclosing function. A
function's length is its lines from its header's first line to its closing
brace. Tests (tests/, *_test.cc) are left out unless --tests.

    scripts/long_functions.py [--limit 150] [--tests] [folders...]

Exits 1 when it lists any.
"""
import argparse
import os
import re
import sys

FOLDERS = ["core", "factors", "backends", "protocol", "conformance", "apps", "plugins", "python"]
NOT_A_FUNCTION = re.compile(
    r"^\s*(?:template\s*<.*>\s*)?(?:namespace|class|struct|union|enum|extern)\b|"
    r"^\s*(?:if|for|while|switch|catch|do|else|try)\b|=\s*$", re.S)

# `Foo::Foo(int a) : a_{a}`: a '{' after a constructor's ':' that follows a
# name, not a ')' or a '}'.
INIT_BRACE = re.compile(r"\)\s*(?:noexcept\s*)?:(?:.|\n)*[\w>]\s*$")


def blank(text):
    """Comments and literals replaced by spaces, newlines kept."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif text.startswith('R"', i) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            m = re.match(r'R"([^(\s]*)\(', text[i:])
            end = text.find(")" + (m.group(1) if m else "") + '"', i)
            j = n if end < 0 else end + len(m.group(1) if m else "") + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c in "\"'":
            if c == "'" and i > 0 and text[i - 1].isalnum():  # digit separator 1'000
                out.append(" ")
                i += 1
                continue
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            j = min(j + 1, n)
            out.append(" " * (j - i))
            i = j
        else:
            out.append(c)
            i += 1
    return "".join(out)


def functions(path):
    """(first line, last line, header) of every function body in `path`."""
    with open(path, encoding="utf-8", errors="replace") as f:
        text = blank(f.read())
    # Preprocessor lines are not code.
    text = re.sub(r"(?m)^\s*#.*(?:\\\n.*)*$", lambda m: re.sub(r"[^\n]", " ", m.group(0)), text)
    found = []
    stack = []  # per open brace: True when it is a function body or inside one
    start = 0   # where the current header began
    for i, c in enumerate(text):
        if c == ";":
            start = i + 1
        elif c == "{":
            header = text[start:i]
            inside = bool(stack) and stack[-1][0]
            if not inside and INIT_BRACE.search(header):
                # A member's brace initialiser in a constructor's list: the
                # header goes on past its '}'.
                stack.append((False, None, 0, ""))
                continue
            body = (not inside and "(" in header and ")" in header
                    and not NOT_A_FUNCTION.search(header.strip() + (" " if header.strip() else "")))
            # A brace-initialiser at namespace scope (`T x{...}` or `= {`) has no ')' before it
            # and falls through as not a function.
            if body and re.search(r"=\s*$", header):
                body = False
            first = text.count("\n", 0, start + len(header) - len(header.lstrip())) + 1
            stack.append((inside or body, body, first, " ".join(header.split())))
            start = i + 1
        elif c == "}":
            if stack:
                _, body, first, header = stack.pop()
                if body is None:
                    continue
                if body:
                    found.append((first, text.count("\n", 0, i) + 1, header))
            start = i + 1
    return found


def source_files(folders, tests=False):
    """(path relative to the repository, absolute path) of every .cc and .h
    below `folders`, sorted; tests/ and *_test.cc only with `tests`."""
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    folders = folders + (["tests"] if tests and "tests" not in folders else [])
    for folder in folders:
        for dirpath, dirnames, filenames in os.walk(os.path.join(root, folder)):
            dirnames[:] = sorted(d for d in dirnames if d != "build")
            for name in sorted(filenames):
                if not name.endswith((".cc", ".h")):
                    continue
                if not tests and name.endswith("_test.cc"):
                    continue
                path = os.path.join(dirpath, name)
                yield os.path.relpath(path, root), path


def list_offenders(doc, limit, measure, what):
    """The command line both house-rule scripts share: `measure(path)`
    gives (size, line, name) per item of a file; the items over --limit are
    printed, the largest first, and the exit status is 1 when there are
    any."""
    parser = argparse.ArgumentParser(description=doc.split("\n\n")[0])
    parser.add_argument("folders", nargs="*", default=FOLDERS)
    parser.add_argument("--limit", type=int, default=limit)
    parser.add_argument("--tests", action="store_true", help="include tests/ and *_test.cc")
    args = parser.parse_args()
    rows = [(size, rel, line, name)
            for rel, path in source_files(args.folders, args.tests)
            for size, line, name in measure(path) if size > args.limit]
    rows.sort(key=lambda r: (-r[0], r[1], r[2]))
    for size, path, line, name in rows:
        print(f"{size:5d}  {path}:{line}  {name[:100]}")
    print(f"{len(rows)} {what.format(limit=args.limit)}", file=sys.stderr)
    return 1 if rows else 0


def main():
    return list_offenders(
        __doc__, 150,
        lambda path: [(last - first + 1, first, header) for first, last, header in functions(path)],
        "function(s) over {limit} lines")


if __name__ == "__main__":
    sys.exit(main())
