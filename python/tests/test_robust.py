# The robust models through Python (python/README.md, "What it holds",
# robust loop closures): the back-ends take robust=gnc / pcm / pcm+gnc as hamal_solve's
# do, refuse the models that change the factors, and run() ends with the
# back-end's closing verdict, so a robust answer in doubt is not ok here
# either.
import os
import subprocess

import pytest

import hamal


def test_gnc_and_pcm_are_backend_options(world):
    g, _ = world
    for spec in ("aprilsam:robust=gnc", "cholesky:robust=pcm", "aprilsam-top:robust=pcm+gnc"):
        r = hamal.run(g, spec)
        assert r.status.ok, (spec, r.status)
        assert r.not_ok == 0
        assert r.chi2 == pytest.approx(hamal.run(g, spec.split(":")[0]).chi2, rel=1e-6)


@pytest.mark.parametrize("model", ["cauchy", "huber", "dcs", "maxmix"])
def test_models_that_change_the_factors_are_refused(model):
    with pytest.raises(hamal.Error, match=f"robust={model} changes the loop closures' factors"):
        hamal.backend(f"aprilsam:robust={model}")


def test_a_backend_without_checks_has_an_ok_closing_verdict(world):
    g, _ = world
    b = hamal.backend("cholesky")
    hamal.run(g, b)
    assert b.closing_verdict().ok


def _spoiled_components_world(tmp_path):
    tools = {name: os.environ.get(f"HAMAL_{name.upper()}") for name in ("generate", "spoil")}
    if not all(tools.values()):
        pytest.skip("HAMAL_GENERATE and HAMAL_SPOIL (build/apps) not given")
    clean, spoiled = tmp_path / "components.g2o", tmp_path / "components-r100-s1.g2o"
    subprocess.run([tools["generate"], "--poses", "2000", "--seed", "13", "--components", "2",
                    "--output", str(clean)], check=True, capture_output=True)
    subprocess.run([tools["spoil"], "--data", str(clean), "--outliers", "100", "--policy", "random",
                    "--seed", "1", "--output", str(spoiled)], check=True, capture_output=True)
    return hamal.read_graph(str(spoiled))


# The judging world of backends/robust/DOUBT.md where GNC keeps a false
# closure to the last update and only the closing check, over every closure,
# finds the cheaper map: reported by default, adopted with gnc_closing=adopt.
def test_the_closing_verdict_reaches_run(tmp_path):
    g = _spoiled_components_world(tmp_path)
    reported = hamal.run(g, "aprilsam:robust=gnc")
    assert reported.results[-1].status.ok
    assert reported.status.code == "uncertain"
    assert "cheaper alternative" in reported.status.message
    assert reported.not_ok >= 1
    adopted = hamal.run(g, "aprilsam:robust=gnc,gnc_closing=adopt")
    assert adopted.status.ok, adopted.status
    assert adopted.chi2 != pytest.approx(reported.chi2, rel=1e-3)
