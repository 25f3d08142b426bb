# hamal.compare reports its progress (to stderr unless silenced) and
# hamal.table shows every time in the unit that shows it (python/hamal/run.py).
import io

import numpy as np
import pytest

import hamal
from conftest import square_world


@pytest.mark.parametrize("seconds, text", [
    (3.4e-6, "3.40 us"), (3.4567e-5, "34.6 us"), (0.000999, "999 us"), (0.0009996, "1.00 ms"),
    (0.0123, "12.3 ms"), (0.5, "500 ms"), (1.5, "1.50 s"), (85.0, "85.0 s"), (1234.5, "1234 s"),
    (1.2e-7, "120 ns"), (0.0, "0 s"), (-2e-3, "-2.00 ms"), (float("nan"), "nan s"),
    (np.float64(2.5e-6), "2.50 us"),
])
def test_format_seconds(seconds, text):
    assert hamal.format_seconds(seconds) == text


class FakeRun:
    def __init__(self, spec, seconds):
        self.spec, self.seconds = spec, np.asarray(seconds)
        self.results = [None] * len(seconds)
        self.batches, self.chi2, self.not_ok = 1, 2.5, 0


def test_the_table_shows_microsecond_medians():
    seconds = np.full(101, 3.4e-6)
    seconds[-1] = 0.02
    text = hamal.table([FakeRun("fast", seconds), FakeRun("slow", [1.2, 2.0, 2.5])])
    header, _, fast, slow = text.splitlines()
    assert header.split() == ["back-end", "steps", "total", "p50", "p99", "max", "batches", "final",
                              "chi2", "not", "ok"]
    cells = fast.split()
    assert cells[:2] == ["fast", "101"]
    assert " 3.40 us " in fast and " 20.0 ms " in fast  # the median, the slowest
    assert " 2.00 s " in slow and " 2.50 s " in slow and "5.70 s" in slow


def test_compare_reports_progress_to_a_stream_and_is_silent_when_asked(capsys):
    g, _ = square_world(30)
    stream = io.StringIO()
    runs = hamal.compare(g, ["cholesky", "aprilsam"], progress=stream)
    lines = stream.getvalue().splitlines()
    assert [len(r.results) for r in runs] == [30, 30]
    for spec in ("cholesky", "aprilsam"):
        mine = [line for line in lines if line.startswith(spec + ":")]
        assert len(mine) == 11  # each tenth of the steps, then the total
        assert mine[0].startswith(f"{spec}: step 3/30 (10%), ")
        assert mine[-1].startswith(f"{spec}: 30 steps in ")
    hamal.compare(g, ["cholesky"], max_steps=5, progress=False)
    assert capsys.readouterr().err == ""
    hamal.compare(g, ["cholesky"], max_steps=5)  # the default: stderr
    err = capsys.readouterr().err
    assert "cholesky: step 5/5 (100%)" in err and "cholesky: 5 steps in " in err


def test_run_is_silent_by_default(capsys):
    g, _ = square_world(8)
    r = hamal.run(g, "cholesky")
    assert capsys.readouterr().err == "" and len(r.seconds) == 8 and r.not_ok == 0


def test_progress_on_a_terminal_rewrites_one_line():
    class Terminal(io.StringIO):
        def isatty(self):
            return True

    g, _ = square_world(10)
    stream = Terminal()
    hamal.run(g, "cholesky", progress=stream)
    text = stream.getvalue()
    assert text.startswith("\r") and text.count("\n") == 1 and "cholesky: 10 steps in " in text


def test_a_run_shows_as_an_html_table_in_jupyter():
    g, _ = square_world(8)
    r = hamal.run(g, "cholesky")
    html = r._repr_html_()
    assert html.startswith("<table>") and html.count("<tr>") == 2
    assert "<th>p50</th>" in html and f"<td>{hamal.format_seconds(np.median(r.seconds))}</td>" in html
    assert "&lt;" in hamal.table_html([FakeRun("<spec>", [1e-3])])
