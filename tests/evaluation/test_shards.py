"""``--shard i/N``: complete, disjoint, deterministic; bad values refused; a shard's record."""

from __future__ import annotations

import json
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest

from sdar_tamp.cli import main
from sdar_tamp.errors import ParameterError
from sdar_tamp.evaluation.rerun import bench_commands
from sdar_tamp.evaluation.results import COMBINATIONS, RESULTS, load_results
from sdar_tamp.evaluation.runner import run_bench
from sdar_tamp.evaluation.settings import SETTINGS, SettingsMismatch, read_settings
from sdar_tamp.evaluation.shards import Shard, parse_shard, shard_of
from sdar_tamp.evaluation.suite import suite_entries

FinishedFolder = Callable[..., Path]

PAIRS = [(e.name, c.id) for e in suite_entries("paper") for c in COMBINATIONS]


@pytest.mark.parametrize("count", [1, 2, 3, 7])
def test_shards_partition_the_pairs(count: int) -> None:
    parts = [
        {p for p in PAIRS if Shard(i, count).takes(*p)} for i in range(1, count + 1)
    ]  # fmt: skip
    assert set().union(*parts) == set(PAIRS)  # complete
    assert sum(len(p) for p in parts) == len(PAIRS)  # disjoint
    assert all(parts)  # 222 pairs: no shard is empty
    assert all(1 <= shard_of(i, c, count) <= count for i, c in PAIRS)


def test_a_pairs_shard_depends_on_its_names_only() -> None:
    """The same in another interpreter (another hash seed), and not on the selection."""
    here = [shard_of(i, c, 5) for i, c in PAIRS]
    code = (
        "from sdar_tamp.evaluation.shards import shard_of;"
        f"print([shard_of(i, c, 5) for i, c in {PAIRS!r}])"
    )
    there = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True,
        env={"PYTHONHASHSEED": "123", "PYTHONPATH": str(Path(__file__).resolve().parents[2])},
    ).stdout  # fmt: skip
    assert here == json.loads(there)
    # the documented rule, pinned: SHA-256 of "instance/combination", modulo N, plus 1
    assert shard_of("R4", "sdar", 4) == 3 and shard_of("M10", "baseline", 4) == 1


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("0/4", r"i must be in 1\.\.4 for N = 4, got 0"),
        ("5/4", r"i must be in 1\.\.4 for N = 4, got 5"),
        ("1/0", "N must be >= 1, got 0"),
        ("3", "shard must be i/N"),
        ("a/b", "shard must be i/N"),
        ("-1/2", "shard must be i/N"),
        ("1/2/3", "shard must be i/N"),
        ("", "shard must be i/N"),
    ],
)
def test_bad_shard_values(text: str, message: str) -> None:
    with pytest.raises(ParameterError, match=message):
        parse_shard(text)


def test_bad_shard_on_the_command_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "out"
    assert main(["bench", "--out", str(out), "--only", "R4", "--shard", "3/2", "-q"]) == 2
    assert "i must be in 1..2" in capsys.readouterr().err
    assert not out.exists()  # refused before anything is written


def test_a_shard_runs_its_pairs_and_is_recorded(
    tmp_path: Path, finished_folder: FinishedFolder
) -> None:
    """Every pair of shard 2/3 of R4, S4 is finished: nothing runs, the record says 2/3 and a
    rerun with another shard into the same folder is refused."""
    names = ["R4", "S4"]
    shard = Shard(2, 3)
    pairs = [(n, c.id) for n in names for c in COMBINATIONS if shard.takes(n, c.id)]
    finished_folder(tmp_path, pairs)
    before = (tmp_path / RESULTS).read_text()
    run_bench("paper", tmp_path, "all", instances=names, shard="2/3", progress=False)
    assert (tmp_path / RESULTS).read_text() == before  # nothing else ran
    settings = read_settings(tmp_path)
    assert settings is not None and settings.shard == "2/3"
    assert json.loads((tmp_path / SETTINGS).read_text())["backend"] == "process"
    with pytest.raises(SettingsMismatch, match=r"shard 1/3 \(the rows: 2/3\)"):
        run_bench("paper", tmp_path, "all", instances=names, shard="1/3", progress=False)
    with pytest.raises(SettingsMismatch, match=r"shard none \(the rows: 2/3\)"):
        run_bench("paper", tmp_path, "all", instances=names, progress=False)
    (command,) = bench_commands(tmp_path, settings, load_results(tmp_path), ["R4", "S4", "D4"])
    assert command.endswith("--seed 0 --shard 2/3 --only R4,S4"), command
