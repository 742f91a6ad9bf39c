"""One-line refusals the command line owes its user: flags a run would ignore, an --svg that is not
SVG, a mistyped flag blamed on its subcommand with the closest flag, and every subcommand's help
saying its exit codes and defaults; and the summary's words (plurals, cycles, crashes)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import pytest

from fatswarm.deploy import cli
from fatswarm.deploy.view import summary
from fatswarm.domain.outcome import ExitCode, Status

MODES = pytest.mark.parametrize("mode", [["--lockstep"], []], ids=["lockstep", "networked"])

pytestmark = pytest.mark.usefixtures("no_launch")  # tests/unit/conftest.py


def refused(capsys: pytest.CaptureFixture[str], prog: str, *words: str) -> str:
    captured = capsys.readouterr()
    assert captured.out == ""
    err = captured.err
    assert err.startswith(f"{prog}: ") and err.count("\n") == 1, err
    for word in words:
        assert word in err, err
    return err


@pytest.fixture
def start_file(tmp_path: Path) -> Path:
    path = tmp_path / "start.json"
    path.write_text(json.dumps({"positions": [[0, 0], [5, 0], [0, 5], [5, 5]]}))
    return path


# --- flags a run would ignore ----------------------------------------------------------------


@MODES
def test_start_beside_init_is_refused(
    mode: list[str], start_file: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["run", *mode, "--init", str(start_file), "--start", "dense", "-q"]
    assert cli.main(argv) == ExitCode.BAD_INPUT
    refused(capsys, "fatswarm run", "--start dense draws a random start", "pass one of them")


@MODES
@pytest.mark.parametrize(
    ("scheduler", "why"),
    [
        ("fsync", "activates every robot in every round"),
        ("async", "has no rounds"),
        ("async-slowest", "has no rounds"),
    ],
)
def test_fairness_for_a_scheduler_that_ignores_it_is_refused(
    mode: list[str], scheduler: str, why: str, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["run", *mode, "--scheduler", scheduler, "--fairness", "3", "-q"]
    assert cli.main(argv) == ExitCode.BAD_INPUT
    refused(
        capsys, "fatswarm run", "--fairness only goes with --scheduler ssync or centralized", why
    )


def test_fairness_still_goes_with_ssync_and_centralized(capsys: pytest.CaptureFixture[str]) -> None:
    for scheduler in ("ssync", "centralized"):
        argv = ["run", "--lockstep", "-n", "4", "--seed", "1", "--scheduler", scheduler]
        assert cli.main([*argv, "--fairness", "3", "-q"]) == ExitCode.FORMED


def test_fairness_with_the_resume_of_an_fsync_run_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    record = tmp_path / "r.jsonl"
    argv = ["run", "--lockstep", "-n", "5", "--seed", "1", "--scheduler", "fsync", "-q"]
    assert cli.main([*argv, "--record", str(record)]) == ExitCode.FORMED
    lines = record.read_text().splitlines(keepends=True)
    record.write_text("".join(lines[:3]))
    capsys.readouterr()
    resume = ["run", "--lockstep", "--record", str(record), "--resume", "--fairness", "2", "-q"]
    assert cli.main(resume) == ExitCode.BAD_INPUT
    refused(capsys, "fatswarm run", "fsync activates every robot")


def test_force_without_a_record_is_refused_in_lock_step(
    capsys: pytest.CaptureFixture[str],
) -> None:
    # networked, --force also lets a run larger than the machine seems to hold start
    assert cli.main(["run", "--lockstep", "-n", "4", "--force", "-q"]) == ExitCode.BAD_INPUT
    refused(capsys, "fatswarm run", "--force lets --record overwrite its file")


# --- --svg -----------------------------------------------------------------------------------


@MODES
@pytest.mark.parametrize("name", ["final.png", "final.PNG.bak", "final"])
def test_an_svg_that_is_not_svg_is_refused_before_the_run(
    mode: list[str], name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    target = tmp_path / name
    argv = ["run", *mode, "-n", "4", "--seed", "1", "-q", "--svg", str(target)]
    assert cli.main(argv) == ExitCode.BAD_INPUT
    refused(capsys, "fatswarm run", "--svg writes the final frame as SVG: name a .svg file")
    assert not target.exists()


def test_an_svg_in_capitals_is_svg(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    target = tmp_path / "final.SVG"
    assert (
        cli.main(["run", "--lockstep", "-n", "4", "--seed", "1", "-q", "--svg", str(target)]) == 0
    )
    assert target.read_text().lstrip().startswith("<svg")


# --- usage errors name the subcommand --------------------------------------------------------


@pytest.mark.parametrize(
    ("argv", "said"),
    [
        (["run", "--seeed", "3"], "fatswarm run: unknown flag --seeed (did you mean --seed?) "),
        (
            ["hunt", "--bugdet-runs=3"],
            "fatswarm hunt: unknown flag --bugdet-runs=3 (did you mean --budget-runs?)",
        ),
        (["sweep", "--sedes", "3"], "fatswarm sweep: unknown flag --sedes (did you mean --seeds?)"),
        (["replay", "x.jsonl", "--robto", "1"], "fatswarm replay: unknown flag --robto"),
        (["hunt", "stray"], "fatswarm hunt: unknown argument stray "),
        (
            ["run", "--sed=3", "--frobnicate"],
            "fatswarm run: unrecognized arguments: --sed=3 (did you mean --seed?) --frobnicate",
        ),
        (
            ["run", "--scheduler", "ssyn"],
            "fatswarm run: argument --scheduler: invalid choice: 'ssyn' (choose from fsync, "
            "ssync, centralized, scripted, async, async-slowest); did you mean ssync? ",
        ),
        (["rnu"], "fatswarm: argument COMMAND: invalid choice: 'rnu' "),
    ],
)
def test_a_usage_error_names_its_subcommand_and_the_closest_flag(
    argv: list[str], said: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert cli.main(argv) == ExitCode.BAD_INPUT
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.count("\n") == 1, captured.err
    assert captured.err.startswith(said), captured.err
    prog = said.split(":")[0]
    assert captured.err.endswith(f"(see {prog} --help)\n"), captured.err


def test_rnu_suggests_run(capsys: pytest.CaptureFixture[str]) -> None:
    cli.main(["rnu"])
    assert "did you mean run?" in capsys.readouterr().err


# --- every subcommand's help -----------------------------------------------------------------


def subcommands() -> dict[str, argparse.ArgumentParser]:
    parser = cli.build_parser()
    (sub,) = (a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return dict(sub.choices)


@pytest.mark.parametrize("name", sorted(cli.COMMANDS))
def test_every_subcommands_help_says_its_exit_codes(name: str) -> None:
    text = " ".join(subcommands()[name].format_help().split())
    assert "exit codes: 0 " in text and " 2 bad input" in text, text


def test_defaults_are_shown_where_the_help_did_not_say_them() -> None:
    helps = {name: " ".join(p.format_help().split()) for name, p in subcommands().items()}
    assert "seed of the random start (default 0)" in helps["world"]
    assert "kind of random start (default clustered)" in helps["world"]
    assert "progress lines: one every K rounds (default 50)" in helps["dashboard"]
    assert "(default 8;" in helps["run"] and "(default 8) (default" not in helps["run"]
    assert "(default rigid: rigid moves)" in helps["hunt"] and "(default none)" in helps["hunt"]


# --- the summary's words ---------------------------------------------------------------------


def outcome(**changes: object) -> summary.Outcome:
    fields: dict[str, object] = {
        "status": Status.FORMED,
        "rounds": 1,
        "collisions": 0,
        "n": 2,
        "a": 4.0,
        "seed": 1,
        "scheduler": "ssync",
        "epochs": 1,
        "moves": 1,
        "total_distance": 1.5,
    }
    fields.update(changes)
    return summary.Outcome(**fields)  # type: ignore[arg-type]


def test_one_round_is_one_round() -> None:
    assert summary.verdict(outcome()) == "formed in 1 round, collision-free"
    assert summary.verdict(outcome(collisions=1)).startswith("formed in 1 round, but with 1 ")
    stopped = outcome(status=Status.MAX_ROUNDS, rounds=1)
    assert summary.verdict(stopped) == "not formed: stopped at the round limit (1 round)"


def test_an_async_run_counts_cycles_in_every_line_of_its_summary() -> None:
    o = outcome(scheduler="async", rounds=164, time=321.5)
    lines = summary.summary(o).splitlines()
    assert lines[0] == "formed in 164 cycles, collision-free"
    assert lines[2].startswith("cycles 164  epochs 1") and lines[3].endswith("virtual time 321.500")
    assert all(len(line) <= 80 for line in lines)
    capped = outcome(scheduler="async-slowest", status=Status.MAX_ROUNDS, rounds=5760)
    assert summary.verdict(capped) == "not formed: stopped at the cycle limit (5760 cycles)"


def test_the_summary_names_the_crashed_robots_and_when(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    record = tmp_path / "crash.jsonl"
    argv = ["run", "--lockstep", "-n", "6", "--crash", "2", "--seed", "1", "-q"]
    assert cli.main([*argv, "--record", str(record)]) == ExitCode.NOT_FORMED
    lines = capsys.readouterr().out.splitlines()
    assert lines[0] == "not formed: stalled after 17 rounds"
    assert "crashed (--crash): robot 4 in round 9, robot 3 in round 11" in lines[3:5]
    assert cli.main([*argv, "--json"]) == ExitCode.NOT_FORMED
    fields = json.loads(capsys.readouterr().out)
    assert fields["crashes"] == [{"robot": 4, "round": 9}, {"robot": 3, "round": 11}]
    from fatswarm.world.record_read import read_record

    assert summary.crashes_in(read_record(record).rounds) == ((4, 9), (3, 11))


def test_a_resumed_crash_run_names_the_crashes_before_and_after_the_break(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    record = tmp_path / "crash.jsonl"
    argv = ["run", "--lockstep", "-n", "6", "--crash", "2", "--seed", "1", "-q"]
    assert cli.main([*argv, "--record", str(record)]) == ExitCode.NOT_FORMED
    whole = capsys.readouterr().out
    record.write_text("".join(record.read_text().splitlines(keepends=True)[:11]))  # 10 rounds
    assert cli.main(["run", "--lockstep", "--record", str(record), "--resume", "-q"]) == 1
    assert capsys.readouterr().out == whole


def test_an_async_crash_is_said_at_the_cycle_it_first_counts_in(
    capsys: pytest.CaptureFixture[str],
) -> None:
    argv = ["run", "--lockstep", "-n", "8", "--crash", "2", "--seed", "8", "-q"]
    assert cli.main([*argv, "--scheduler", "async-slowest"]) == ExitCode.NOT_FORMED
    out = capsys.readouterr().out
    assert "\ncrashed (--crash): robot 4 in cycle 37\n" in out, out


def test_a_run_without_crashes_keeps_its_json_as_before(capsys: pytest.CaptureFixture[str]) -> None:
    assert cli.main(["run", "--lockstep", "-n", "4", "--seed", "1", "--json"]) == 0
    assert "crashes" not in json.loads(capsys.readouterr().out)
