"""Old spellings of the Python runners' options, kept for one release: the
Python side of HAMAL_FLAG_ALIAS (apps/common/cli.h). An old spelling is read
as the option it was renamed to, and a line on stderr names the new one:

    p.add_argument("--output", ...)
    old_spelling(p, "--out", "--output")
"""
import argparse
import sys


class _OldSpelling(argparse.Action):
    def __init__(self, option_strings, dest, new=None, **kwargs):
        self.new = new
        super().__init__(option_strings, dest, **kwargs)

    def __call__(self, parser, namespace, values, option_string=None):
        print(f"{parser.prog}: {option_string} is an old spelling; use {self.new}", file=sys.stderr)
        setattr(namespace, self.dest, values)


def old_spelling(parser, old, new):
    """Accepts `old` as the already added option `new` (same destination,
    type and arity), hidden from --help."""
    target = next(a for a in parser._actions if new in a.option_strings)
    parser.add_argument(old, dest=target.dest, action=_OldSpelling, new=new, type=target.type,
                        nargs=target.nargs, help=argparse.SUPPRESS)
