"""The command line as declared (engine/src/cli, CLI11): a refused command line exits 2 with one
line naming the option and the reason; the help documents the options and the exit codes; the
values reach the run as given (--opt=value, a repeated option's last value, --set beside the
scene); the pass-through commands keep their words."""
import json
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
SILO = REPO / "reference_inputs" / "scenes" / "silo_17_18.toml"


def one_line_error(proc, *fragments):
    assert proc.returncode == 2, proc.stdout + proc.stderr
    assert proc.stderr.count("\n") == 1 and proc.stderr.startswith("dem"), proc.stderr
    for f in fragments:
        assert f in proc.stderr, (f, proc.stderr)


@pytest.mark.parametrize("args,fragments", [
    (("run", SILO, "--out", "o", "--dt", "abc"), ["dem run:", "--dt", '"abc" is not a number > 0']),
    (("run", SILO, "--out", "o", "--dt=-1"), ["--dt", '"-1" is not a number > 0']),
    (("run", SILO, "--out", "o", "--threads", "0"), ["--threads", '"0" is not an integer in [1, 256]']),
    (("run", SILO, "--out", "o", "--scheme", "rk4"), ["--scheme", '"rk4" is none of paper_eq18']),
    (("run", SILO), ["--out", "required"]),
    (("run", "--out", "o"), ["SCENE.toml", "required"]),
    (("run", SILO, "--out", "o", "--frobnicate"), ["--frobnicate", "dem run --help"]),
    (("run", SILO, "--out", "o", "--np", "2"), ["--np requires --engine"]),
    (("run", SILO, "--out", "o", "--set", "nokey"), ["--set", '"nokey" is not KEY=VALUE']),
    (("run", SILO, "--out"), ["--out", "DIR"]),
    (("ensemble", SILO, "--out", "o", "--members", "0"), ["dem ensemble:", "--members", "[1, 10000]"]),
    (("ensemble", "merge"), ["dem ensemble merge:", "DIR", "required"]),
    (("params", "--nu", "0.7"), ["--nu", "0.7"]),
    (("params", "--E", "1e3,x"), ["--E", '"x"']),
    (("params", SILO, "--units", "si"), ["--units", "excludes"]),
    (("resolve",), ["SCENE.toml", "required"]),
    (("frobnicate",), ["unknown command frobnicate", "dem --help"]),
])
def test_a_refused_command_line_exits_2_with_one_line(run_dem, tmp_path, args, fragments):
    proc = run_dem(*[tmp_path / a if a == "o" else a for a in args])
    one_line_error(proc, *fragments)
    assert not (tmp_path / "o").exists()


def test_no_command_prints_the_help_on_stderr_and_exits_2(run_dem):
    proc = run_dem()
    assert proc.returncode == 2 and "usage: dem" in proc.stderr and not proc.stdout


def test_the_help_documents_the_commands_and_the_exit_codes(run_dem):
    text = run_dem("--help").stdout
    for word in ("run", "ensemble", "params", "resolve", "compare", "--version", "--set KEY=VALUE"):
        assert word in text, word
    assert "exit codes: 0 ok, 2 bad input" in text and "3 unstable" in text and "4 a run that could not go on" in text
    assert "130/143" in text
    ens = run_dem("ensemble", "--help").stdout
    assert "3 when every member was unstable" in ens and "4 when every member failed" in ens and "merge" in ens
    run = run_dem("run", "--help").stdout
    for option in ("--out DIR", "--dt S", "--threads N", "--resume", "--pictures", "--engine CODE", "--np N",
                   "--settle S", "--timeout S", "dem.compare.figures run DIR", "exits with 130 (SIGINT) or 143"):
        assert option in run, option
    assert "usage: dem ensemble merge" in run_dem("ensemble", "merge", "--help").stdout


def test_version(run_dem, dem_binary):
    for args in (("--version",), ("version",)):
        proc = run_dem(*args)
        assert proc.returncode == 0 and proc.stdout.startswith("dem 0.") and "(" in proc.stdout, proc.stdout
        # the Python package its dem compare, --pictures and --engine run: this build's
        assert proc.stdout.splitlines()[1] == f"python package: {Path(dem_binary).parent / 'python' / 'dem'}"


def test_values_reach_the_scene_as_given(run_dem, tmp_path):
    """--opt=value, --set before the scene (one value a --set), the last of a repeated option."""
    a, b = tmp_path / "a.json", tmp_path / "b.json"
    proc = run_dem("resolve", "--set", "integrator.dt=5e-5", SILO, "--set=end.time=0.25", "--out", a, f"--out={b}")
    assert proc.returncode == 0, proc.stderr
    assert not a.exists()
    r = json.loads(b.read_text())
    assert r["integrator"]["dt"] == 5e-5 and r["end"]["time"] == 0.25


def test_compare_hands_its_words_on_untouched(run_dem):
    """`dem compare --help` is the comparison layer's help, not a declaration of this program."""
    proc = run_dem("compare", "--help")
    assert proc.returncode == 0 and "--codes" in proc.stdout and "--until-decided" in proc.stdout, proc.stderr
