"""Resumable results: the one check every Python runner (hamal_sweep, the
robust sweep, FLAG's trials) makes before it extends a results folder, with
the rules of apps/common/resumable_results.h (hamal_moss), so that two
experiments' results never mix and a damaged file is never taken as done:

  - the parameters that made the folder are recorded beside its rows; a
    record that differs from this invocation's is refused, naming the first
    parameter that differs; rows without their record are refused;
  - every complete row of a rows file has its header's number of fields
    (else "FILE:LINE: ..."); a last row cut by a kill (no line break) is torn:
    the caller drops it (or the unit that wrote it) and runs it again;
  - a file cut at a line break looks whole, so a runner records how many rows
    a finished file has (count_rows) and compares: fewer is a damaged unit.

Standard library only: it runs on login and compute nodes alike.
"""

import csv
import fcntl
import io
import json
import os

import atomic_json


class ResultsError(SystemExit):
    """A results folder that cannot be extended; the message names the file
    and the line or the parameter."""


def _shown(value):
    """A value as a message shows it: strings quoted, the rest as JSON, cut."""
    text = repr(value) if isinstance(value, str) else json.dumps(value)
    return text if len(text) <= 60 else text[:57] + "..."


def differing_parameter(there, now, prefix=""):
    """The first parameter (dotted for nested records) whose value differs
    between two records, as 'name is X there and Y now'; None when equal."""
    for key in list(now) + [k for k in there if k not in now]:
        name = prefix + str(key)
        if key not in there:
            return f"{name} is not set there and {_shown(now[key])} now"
        if key not in now:
            return f"{name} is {_shown(there[key])} there and not set now"
        a, b = there[key], now[key]
        if isinstance(a, dict) and isinstance(b, dict):
            inner = differing_parameter(a, b, name + ".")
            if inner:
                return inner
        elif a != b:
            return f"{name} is {_shown(a)} there and {_shown(b)} now"
    return None


def read_json(path):
    """A JSON file of a results folder; a damaged one is an error naming it."""
    try:
        with open(path) as f:
            return json.load(f)
    except json.JSONDecodeError as e:
        raise ResultsError(f"{path}:{e.lineno}: not valid JSON ({e.msg}): a damaged "
                           "results file; move it away to redo what wrote it")
    except UnicodeDecodeError as e:
        raise ResultsError(f"{path}: not text ({e.reason}): a damaged results file")


# Written whole or not at all (atomic_json.py).
write_json = atomic_json.write_json


def check_config(path, parameters, has_results, option="--results"):
    """Verifies the record of the parameters that made a folder: refused when it
    differs (naming the parameter), or when it is missing beside results; written
    when the folder is new. Only the keys of both are compared: a record may
    carry more (dates, timings), and keys new to it (a part of the folder made
    for the first time) are added."""
    if not os.path.exists(path):
        if has_results:
            raise ResultsError(f"{path}: missing beside the results there, so nothing says "
                               f"which parameters made them; use another {option}")
        write_json(path, parameters)
        return
    there = read_json(path)
    if not isinstance(there, dict):
        raise ResultsError(f"{path}: not a record of parameters (a JSON object)")
    reason = differing_parameter({k: there[k] for k in parameters if k in there},
                                 {k: parameters[k] for k in parameters if k in there})
    if reason:
        raise ResultsError(f"{path}: this folder holds results of other parameters ({reason}); "
                           f"use another {option}")
    if any(k not in there for k in parameters):  # parameters of new parts of the folder
        write_json(path, dict(there, **parameters))


def gflags_parameters(argv):
    """A C++ tool's flags (gflags) as the parameters they set, {name: value}, the
    last one winning as in gflags: '--gate 3' and '--gate=3' are {'gate': '3'},
    '--nopairwise_check' is {'pairwise_check': 'false'}."""
    options, k = {}, 0
    while k < len(argv):
        name, eq, value = argv[k].lstrip("-").partition("=")
        if not eq and k + 1 < len(argv) and not argv[k + 1].startswith("--"):
            value, k = argv[k + 1], k + 1
        elif not eq:
            value = "true"
            if name.startswith("no"):
                name, value = name[2:], "false"
        options[name] = value
        k += 1
    return options


def read_rows(path, header=None):
    """The rows of a CSV rows file as (rows as dicts, torn): every complete row
    must have the header's number of fields, else ResultsError 'PATH:LINE: ...';
    torn is True when the last row has no line break (cut by a kill), and that
    row is not among the rows. `header`, when given, is the expected column list."""
    with open(path, "rb") as f:
        data = f.read()
    try:
        text = data.decode()
    except UnicodeDecodeError as e:
        raise ResultsError(f"{path}: not text at byte {e.start}: a damaged results file")
    torn = bool(text) and not text.endswith("\n")
    if torn:
        text = text[:text.rfind("\n") + 1]
    lines = text.splitlines()
    if not lines:
        return [], torn
    columns = next(csv.reader([lines[0]]))
    if header is not None and columns != list(header):
        raise ResultsError(f"{path}:1: the header is {_shown(','.join(columns))}, expected "
                           f"{_shown(','.join(header))}: not a results file of this run")
    rows = []
    for number, fields in enumerate(csv.reader(io.StringIO("\n".join(lines[1:]))), 2):
        if len(fields) != len(columns):
            raise ResultsError(f"{path}:{number}: {len(fields)} fields, the header has "
                               f"{len(columns)} (a damaged results file)")
        rows.append(dict(zip(columns, fields)))
    return rows, torn


def count_rows(path):
    """The complete rows of a rows file (its header not counted), which a
    runner records when the file is finished, so that one cut later at a line
    break (which read_rows cannot tell from a shorter run) is seen."""
    return len(read_rows(path)[0])


def drop_torn_row(path):
    """Cuts a rows file back to its last whole row; True when there was a torn one."""
    with open(path, "rb+") as f:
        data = f.read()
        if not data or data.endswith(b"\n"):
            return False
        f.truncate(data.rfind(b"\n") + 1)
    return True


def lock(folder, who):
    """One invocation per results folder: an flock on FOLDER/.lock, held while the
    returned file is open (flock on NFS needs NFSv4 or lockd). `who` starts the
    message of the refused one ("hamal_sweep: another sweep")."""
    os.makedirs(folder, exist_ok=True)
    handle = open(os.path.join(folder, ".lock"), "w")
    try:
        fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        handle.close()
        raise ResultsError(f"{who} is writing to {folder}")
    return handle
