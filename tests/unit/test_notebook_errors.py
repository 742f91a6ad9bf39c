"""`fatswarm.run` refuses bad keywords in its own words: one ValueError naming the keyword (not a
flag of `fatswarm run`, not a traceback from deep inside), for every keyword it takes."""

from __future__ import annotations

import json
import traceback
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import fatswarm
from fatswarm.deploy.engine import api

SIX = {"positions": [[0, 0], [3, 0], [6, 0], [0, 3], [3, 3], [6, 3]], "a": 4.0}


@pytest.fixture
def six(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> str:
    """A start file of six robots, in the working directory."""
    monkeypatch.chdir(tmp_path)
    Path("six.json").write_text(json.dumps(SIX))
    return "six.json"


def refusal(**keywords: Any) -> ValueError:
    """What `fatswarm.run(**keywords)` raises (a short run, were it accepted)."""
    keywords.setdefault("max_rounds", 2)
    with pytest.raises(ValueError) as caught:
        fatswarm.run(**keywords)
    return caught.value


def test_n_against_the_robots_of_init_is_said_with_the_keywords(six: str) -> None:
    said = str(refusal(n=5, init=six))
    assert said == "n=5 disagrees with the 6 robots of init six.json; leave n out"


@pytest.mark.parametrize(
    ("keywords", "says"),
    [
        ({"seed": "1"}, "seed must be an int, got '1'"),
        ({"seed": 1.5}, "seed must be an int, got 1.5"),
        ({"seed": None}, "seed must be an int, got None"),
        ({"seed": True}, "seed must be an int, got True"),
        ({"n": "8"}, "n must be an int or None, got '8'"),
        ({"n": 2.5}, "n must be an int or None, got 2.5"),
        ({"algorithm": 3}, "algorithm must be a str, got 3"),
        ({"params": [1]}, "params must be a dict of names to values, got [1]"),
        ({"params": {1: 2}}, "params must be a dict of names to values, got {1: 2}"),
        ({"start": 3}, "start must be a str, got 3"),
        ({"positions": "x"}, "positions must be an (n, 2) array of numbers, got 'x'"),
        ({"positions": [[0, 0], [3, "a"]]}, "positions must be an (n, 2) array of numbers, got"),
        ({"init": 3}, "init must be a path (str or os.PathLike), got 3"),
        ({"scheduler": None}, "scheduler must be a str, got None"),
        ({"schedule": 3.0}, "schedule must be a path (str or os.PathLike), got 3.0"),
        ({"fairness": "2"}, "fairness must be an int or None, got '2'"),
        ({"max_rounds": 2.5}, "max_rounds must be an int or None, got 2.5"),
        ({"non_rigid": "1"}, "non_rigid must be a number or None, got '1'"),
        ({"crash": 1.5}, "crash must be an int or None, got 1.5"),
        ({"visibility": None}, "visibility must be a str, got None"),
        ({"sight": "3"}, "sight must be a number or None, got '3'"),
        ({"lights": 1}, "lights must be a str, got 1"),
        ({"frames": 1}, "frames must be a str, got 1"),
        ({"frame_change": 1}, "frame_change must be a str, got 1"),
        ({"record_views": "yes"}, "record_views must be True or False, got 'yes'"),
        ({"record": 3}, "record must be a path (str or os.PathLike), got 3"),
        ({"on_round": 3}, "on_round must be a function or None, got 3"),
    ],
)
def test_a_keyword_of_the_wrong_type_is_named(keywords: dict[str, Any], says: str) -> None:
    error = refusal(**keywords)
    assert isinstance(error, api.RunArgumentError) and isinstance(error, TypeError)
    assert str(error).startswith(says), str(error)


@pytest.mark.parametrize(
    ("keywords", "says"),
    [
        ({"max_rounds": 0}, "max_rounds must be at least 1, got 0"),
        ({"non_rigid": 0}, "non_rigid must be a finite distance > 0 (robot radii), got 0"),
        ({"crash": 9}, "crash must be between 1 and n - 1 = 7, got 9"),
        ({"schedule": "s.json"}, "schedule only goes with scheduler='scripted'"),
        ({"scheduler": "scripted"}, "the scripted scheduler needs a schedule file (schedule=PATH)"),
        ({"lights": "internal"}, "lights='internal' needs an algorithm with lights"),
        ({"visibility": "x"}, "visibility must be one of transparent, opaque, opaque-centres"),
        ({"sight": -1}, "sight must be a finite distance > 0 (robot radii), got -1"),
        ({"frame_change": "x"}, "frame_change must be one of fixed, every-look, got 'x'"),
        ({"algorithm": "nowhere:thing"}, "algorithm 'nowhere:thing': cannot import"),
    ],
)
def test_a_refusal_worded_for_flags_is_worded_for_keywords(
    keywords: dict[str, Any], says: str
) -> None:
    said = str(refusal(**keywords))
    assert said.startswith(says), said
    assert "--" not in said and "-n " not in said


def test_flag_words_become_keywords_wherever_they_are() -> None:
    assert api.api_words("--fairness only goes with --scheduler ssync or centralized") == (
        "fairness only goes with scheduler='ssync' or 'centralized'"
    )
    assert api.api_words("--schedule only goes with --scheduler scripted") == (
        "schedule only goes with scheduler='scripted'"
    )
    assert (
        api.api_words("it activates all: drop --fairness") == "it activates all: leave fairness out"
    )
    assert api.api_words("--start does not go with --init") == "start does not go with init"
    assert api.api_words("--resume: nothing; see --help") == "--resume: nothing; see --help"
    assert api.api_words("give the side once: -a or --param a=..., not both") == (
        "give the side once: params={'a': ...}, not both"
    )
    assert api.api_words("crash must be between 1 and n - 1 = 7") == (
        "crash must be between 1 and n - 1 = 7"
    )


def test_a_refusal_ends_at_the_api_not_deep_inside(six: str) -> None:
    error = refusal(n=5, init=six)
    frames = traceback.extract_tb(error.__traceback__)
    assert frames[-1].name == "run" and frames[-1].filename.endswith("api.py")


def test_numpy_numbers_are_taken_as_numbers() -> None:
    numbers: dict[str, Any] = {
        "seed": np.int64(2),
        "max_rounds": np.int32(3),
        "sight": np.float32(8),
    }
    result = fatswarm.run(np.int64(4).item(), **numbers)
    assert (result.n, result.seed) == (4, 2) and result.rounds <= 3
    keywords: dict[str, Any] = {"n": np.int64(4), "max_rounds": 1}
    assert fatswarm.run(**keywords).n == 4
