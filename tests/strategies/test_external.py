"""``external``: a dispatcher in another language plays the rounds through JSON lines; a Perl MB gives MB's
event log; a program that fails is one line naming it, exit status 2, nothing written."""

from __future__ import annotations

import shutil
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from helpers import line_network, round_state

from rpbench.cli import main
from rpbench.exceptions import ParameterError
from rpbench.strategies.edges import model_from_decision, model_from_scores, round_edges

ROOT = Path(__file__).resolve().parents[2]
PERL_MB = ROOT / "examples" / "dispatchers" / "mb.pl"
TOY = ["--scenario", "toy", "--sample", "0.2", "--no-progress"]


def run(capsys, *args) -> tuple[int, str]:
    code = main([str(a) for a in args])
    return code, capsys.readouterr().err


PERL = pytest.mark.skipif(shutil.which("perl") is None, reason="no perl on this machine")


@PERL
def test_a_perl_mb_plays_the_rounds_as_mb_does(tmp_path, capsys):
    out = tmp_path / "run"
    code, err = run(
        capsys, "run", *TOY, "--strategies", "mb,external", "--opt", f"external.command=perl {PERL_MB}", "--out", out
    )
    assert code == 0, err
    assert_same_decisions(out)


@PERL
@pytest.mark.haikou
def test_the_perl_mb_plays_a_haikou_peak_hour_as_mb_does(data_dir, tmp_path, capsys):
    out = tmp_path / "run"
    args = ["--scenario", "haikou-peak", "--data", data_dir, "--no-progress", "--strategies", "mb,external,bound"]
    code, err = run(capsys, "run", *args, "--opt", f"external.command=perl {PERL_MB}", "--out", out)
    assert code == 0, err
    assert_same_decisions(out)


def assert_same_decisions(out: Path) -> None:
    """MB's and the external run's event logs are the same, round by round, and the folder passes check."""
    mb, ext = (pd.read_csv(out / "runs" / r / "events.csv.gz") for r in ("mb", "external"))
    same = [c for c in mb.columns if c != "utility_m"]
    pd.testing.assert_frame_equal(mb[same], ext[same])  # the same decisions, round by round
    assert np.allclose(mb["utility_m"], ext["utility_m"], rtol=1e-9, equal_nan=True)  # scores in JSON text
    assert main(["check", str(out)]) == 0


def write_program(tmp_path: Path, body: str) -> str:
    """A Python dispatcher whose round answer is ``body`` (an expression of the round message ``m``)."""
    path = tmp_path / "dispatcher.py"
    path.write_text(
        "import json, sys, time\n"
        "for line in sys.stdin:\n"
        "    m = json.loads(line)\n"
        "    if m['type'] == 'end':\n"
        "        break\n"
        "    if m['type'] != 'round':\n"
        "        continue\n"
        f"    {body}\n"
        "    sys.stdout.flush()\n"
    )
    return f"{sys.executable} {path}"


@pytest.mark.parametrize(
    ("body", "options", "message"),
    [
        ("sys.exit(3)", [], "s (it exited with status 3)"),
        ("time.sleep(5)", ["external.time_limit_s=0.5"], "s within its 0.5 s"),
        ("print('hello')", [], "'hello', which is not a JSON line"),
        ("print(json.dumps({'scores': [0] * 3}))", [], "3 numbers for the round's"),
        ("print(json.dumps({'answer': 1}))", [], 'expected an object {"scores": [...]}'),
        (
            "print(json.dumps({'decision': [1] * len(m['edges'])}))",
            ["external.mode=decision"],
            "edges chosen; at most one",
        ),
        ("print(json.dumps({'decision': [2] * len(m['edges'])}))", ["external.mode=decision"], "each edge is 0 or 1"),
    ],
)
def test_a_dispatcher_that_fails_is_one_line_and_writes_nothing(tmp_path, capsys, body, options, message):
    command = write_program(tmp_path, body)
    opts = [a for o in [f"external.command={command}", *options] for a in ("--opt", o)]
    out = tmp_path / "run"
    code, err = run(capsys, "run", *TOY, "--strategies", "external", *opts, "--out", out)
    lines = err.strip().splitlines()
    assert code == 2 and lines[-1].startswith("rpbench: error: external dispatcher"), err
    assert message in lines[-1], lines[-1]
    assert not out.exists()


def test_a_program_that_cannot_start_and_a_missing_command(tmp_path, capsys):
    code, err = run(capsys, "run", *TOY, "--strategies", "external", "--opt", "external.command=/no/such/program")
    assert code == 2 and "cannot start '/no/such/program'" in err
    code, err = run(capsys, "run", *TOY, "--strategies", "external")
    assert code == 2 and "give the dispatcher program with --opt external.command=" in err


def test_a_decision_is_the_only_optimum_of_its_model_and_a_bad_one_is_refused():
    net = line_network(6)
    state = round_state(net, passengers=[(0, 5), (1, 4)], vacant=[(2, 0.0), (3, 0.0)])
    edges = round_edges(state)
    assert list(edges.kind[edges.passenger == 0]) == [0, 0, 2]  # vacant, vacant, wait per passenger
    chosen = np.zeros(len(edges))
    first_vacant = np.flatnonzero((edges.passenger == 0) & (edges.kind == 0))[1]
    chosen[first_vacant] = 1
    rm = model_from_decision(state, edges, chosen, name="test")
    best = np.flatnonzero(rm.utility_m == rm.utility_m.max())
    assert len(best) == 1 and rm.vehicle[best[0]] == edges.vehicle[first_vacant]
    with pytest.raises(ParameterError, match="vehicle .* has 2 edges chosen"):
        both = chosen.copy()
        both[np.flatnonzero((edges.passenger == 1) & (edges.vehicle == edges.vehicle[first_vacant]))] = 1
        model_from_decision(state, edges, both, name="test")
    scored = model_from_scores(state, edges, -np.nan_to_num(edges.pickup_m, nan=1e6), name="test")
    assert scored.model.n_cols == len(edges)


def test_the_documented_minimal_dispatcher_plays_as_mb(tmp_path, capsys):
    """docs/protocol.md's Python example, as written there, gives MB's decisions."""
    text = (ROOT / "docs" / "protocol.md").read_text()
    code = text.split("```python\n", 1)[1].split("```", 1)[0]
    (tmp_path / "my_dispatcher.py").write_text(code)
    out = tmp_path / "run"
    command = f"external.command={sys.executable} {tmp_path / 'my_dispatcher.py'}"
    status, err = run(capsys, "run", *TOY, "--strategies", "mb,external", "--opt", command, "--out", out)
    assert status == 0, err
    kpis = pd.read_csv(out / "kpis.csv").pivot(index="kpi", columns="run", values="value")
    assert kpis.loc["total_saving_km", "external"] == pytest.approx(kpis.loc["total_saving_km", "mb"])
