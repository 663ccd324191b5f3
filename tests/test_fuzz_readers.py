"""Fuzzing the readers of user files: whatever the bytes, only the project's errors escape.

Seeds are the shipped domains, problems and stream files, a shipped instance and a generated
plan file; mutations work on bytes (inserted brackets, control characters, bytes that are not
UTF-8, deep nesting), on tokens (PDDL) and on values (YAML and JSON), so that many examples get
past the syntax into the checks behind it. Examples are derandomised (same every run) and no
example database is written; Hypothesis keeps its caches in the system's temporary folder,
not in the working directory. ``SDAR_FUZZ_EXAMPLES=5000`` runs more, random, examples.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.configuration import set_hypothesis_home_dir

from sdar_tamp.errors import SdarError
from sdar_tamp.language import parse_domain, parse_problem, parse_stream_file
from sdar_tamp.language.domain_model import Domain
from sdar_tamp.plan_building import GripperEvent, MotionSegment, build_plan_file
from sdar_tamp.plan_file import PlanFile
from sdar_tamp.plan_reading import load_plan
from sdar_tamp.plan_writing import save_plan
from sdar_tamp.textfile import decode_text
from sdar_tamp.world.instance import load_instance
from sdar_tamp.world.scene import load_scene
from sdar_tamp.world.transforms import pose_xyz_yaw

DOMAINS = Path(__file__).resolve().parents[1] / "domains"
FUZZ = settings(
    max_examples=int(os.environ.get("SDAR_FUZZ_EXAMPLES", "200")),
    deadline=None,
    derandomize="SDAR_FUZZ_EXAMPLES" not in os.environ,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)


# Hypothesis caches facts about the code under test in ".hypothesis" of the working directory,
# already while pytest collects the tests: keep them in the temporary folder instead.
set_hypothesis_home_dir(Path(tempfile.gettempdir()) / "sdar-tamp-hypothesis")

# Fragments that tend to reach corners: brackets, PDDL keywords, YAML and JSON syntax, control
# characters, bytes that are not UTF-8 (a lone continuation byte, a cut multi-byte sequence),
# a byte-order mark, odd line breaks and numbers.
FRAGMENTS = [
    b"(", b")", b"((((", b"))))", b";", b"\n", b"\r", b"\t", b" ", b"?x", b" - ", b"-",
    b"(and ", b"(not ", b"(or ", b"(forall (?z) ", b"(exists (?z - object) ", b"(when ",
    b":action", b":parameters", b":effect", b":inputs", b":certified", b"(increase (total-cost) ",
    b"[", b"]", b"{", b"}", b'"', b"'", b":", b",", b"- ", b"&a ", b"*a", b"!!int ", b"!!float ",
    b"!!timestamp ", b"2001-13-45", b"<<: ", b"? ", b"|", b"1e999", b"-1", b".nan", b"NaN",
    b"99999999999999999999999999", b"\x00", b"\x07", b"\x1b", b"\x7f", b"\xff", b"\x80", b"\xc3",
    b"\xe2\x82", "\u00e9".encode(), "\u2028".encode(), "\u0130".encode(), b"\xef\xbb\xbf",
]  # fmt: skip
BRACKETS = [(b"(", b")"), (b"[", b"]"), (b"{", b"}"), (b"- ", b"\n")]


@st.composite
def byte_mutants(draw: st.DrawFn, seeds: list[bytes]) -> bytes:
    """A seed with one to four byte-level edits."""
    data = bytearray(draw(st.sampled_from(seeds)))
    for _ in range(draw(st.integers(1, 4))):
        i = draw(st.integers(0, len(data)))
        j = draw(st.integers(i, min(len(data), i + 80)))
        op = draw(st.sampled_from(["delete", "insert", "duplicate", "byte", "truncate", "nest"]))
        if op == "delete":
            del data[i:j]
        elif op == "insert":
            data[i:i] = draw(st.sampled_from(FRAGMENTS)) * draw(st.sampled_from([1, 1, 2, 30]))
        elif op == "duplicate":
            data[j:j] = data[i:j]
        elif op == "byte" and i < len(data):
            data[i] = draw(st.integers(0, 255))
        elif op == "truncate":
            del data[i:]
        elif op == "nest":
            opening, closing = draw(st.sampled_from(BRACKETS))
            depth = draw(st.sampled_from([1, 3, 99, 101, 500, 3000]))
            data[i:j] = opening * depth + bytes(data[i:j]) + closing * depth
    return bytes(data)


_TOKEN = re.compile(rb"[()]|[^\s();]+")
_COMMENT = re.compile(rb";[^\n]*")


@st.composite
def token_mutants(draw: st.DrawFn, seeds: list[bytes]) -> bytes:
    """A PDDL seed with tokens deleted, repeated, swapped for other tokens of the file, or with
    a parenthesis added: the text stays readable, so the parsers' checks are exercised."""
    tokens = _TOKEN.findall(_COMMENT.sub(b"", draw(st.sampled_from(seeds))))
    symbols = [t for t in tokens if t not in (b"(", b")")]
    for _ in range(draw(st.integers(1, 3))):
        i = draw(st.integers(0, len(tokens) - 1))
        op = draw(st.sampled_from(["delete", "repeat", "replace", "paren"]))
        if op == "delete":
            del tokens[i]
        elif op == "repeat":
            tokens.insert(i, tokens[i])
        elif op == "replace":
            tokens[i] = draw(st.sampled_from(symbols))
        else:
            tokens.insert(i, draw(st.sampled_from([b"(", b")"])))
    return b" ".join(tokens)


JSON_VALUES = st.recursive(
    st.none()
    | st.booleans()
    | st.integers(-(2**70), 2**70)
    | st.floats(allow_nan=True, allow_infinity=True)
    | st.text(max_size=6)
    | st.sampled_from(["left", "right", "grasp", "release", "o1", "sdar-plan", "m", "rad"]),
    lambda children: (
        st.lists(children, max_size=4) | st.dictionaries(st.text(max_size=6), children, max_size=4)
    ),
    max_leaves=12,
)


@st.composite
def value_mutants(draw: st.DrawFn, seed: Any) -> Any:
    """A copy of a JSON-like ``seed`` with one to three values replaced, removed or added."""
    data = json.loads(json.dumps(seed))
    for _ in range(draw(st.integers(1, 3))):
        parent: Any = None
        key: Any = None
        node = data
        while isinstance(node, dict | list) and node and draw(st.integers(0, 3)) > 0:
            keys = list(node) if isinstance(node, dict) else list(range(len(node)))
            parent, key = node, draw(st.sampled_from(keys))
            node = node[key]
        if parent is None:
            continue
        op = draw(st.sampled_from(["replace", "replace", "remove", "add"]))
        if op == "replace":
            parent[key] = draw(JSON_VALUES)
        elif op == "remove":
            del parent[key]
        elif isinstance(parent, dict):
            parent[draw(st.text(max_size=6))] = draw(JSON_VALUES)
        else:
            parent.append(draw(JSON_VALUES))
    return data


def _only_project_errors(read: Callable[[], object]) -> None:
    """Run ``read``; an error that is not an :class:`SdarError` fails the test."""
    with contextlib.suppress(SdarError):
        read()


# -- seeds -------------------------------------------------------------------------------------
def _pddl_files(pattern: str) -> list[Path]:
    return sorted(DOMAINS.glob(pattern))


DOMAIN_FILES = _pddl_files("*/domain.pddl")
DOMAIN_SEEDS = [p.read_bytes() for p in DOMAIN_FILES]
PROBLEM_FILES = _pddl_files("*/problems/*.pddl")
STREAM_FILES = _pddl_files("*/stream.pddl")
INSTANCE_FILE = DOMAINS / "dual_arm_rearrangement" / "suites" / "paper" / "R4.yaml"


def _domain_of(path: Path) -> Domain:
    """The domain of a problem (``X/problems/p.pddl``) or stream file (``X/stream.pddl``)."""
    folder = path.parent.parent if path.parent.name == "problems" else path.parent
    domain_path = folder / "domain.pddl"
    return parse_domain(domain_path.read_text(encoding="utf-8"), str(domain_path))


def _decoded(data: bytes, name: str) -> str:
    return decode_text(data, name)


# -- PDDL --------------------------------------------------------------------------------------
@FUZZ
@given(data=st.one_of(byte_mutants(DOMAIN_SEEDS), token_mutants(DOMAIN_SEEDS)))
def test_domain_parser(data: bytes) -> None:
    _only_project_errors(lambda: parse_domain(_decoded(data, "domain.pddl"), "domain.pddl"))


PROBLEMS = [(_domain_of(p), p.read_bytes()) for p in PROBLEM_FILES]


@FUZZ
@given(
    index=st.integers(0, len(PROBLEMS) - 1),
    mutate=st.sampled_from([byte_mutants, token_mutants]),
    choice=st.data(),
)
def test_problem_parser(index: int, mutate: Any, choice: st.DataObject) -> None:
    domain, seed = PROBLEMS[index]
    data = choice.draw(mutate([seed]))
    _only_project_errors(lambda: parse_problem(_decoded(data, "p.pddl"), domain, "p.pddl"))


STREAMS = [(_domain_of(p), p.read_bytes()) for p in STREAM_FILES]


@FUZZ
@given(
    index=st.integers(0, len(STREAMS) - 1),
    mutate=st.sampled_from([byte_mutants, token_mutants]),
    choice=st.data(),
)
def test_stream_file_parser(index: int, mutate: Any, choice: st.DataObject) -> None:
    domain, seed = STREAMS[index]
    data = choice.draw(mutate([seed]))
    _only_project_errors(lambda: parse_stream_file(_decoded(data, "s.pddl"), domain, "s.pddl"))


# -- instance YAML -----------------------------------------------------------------------------
INSTANCE_SEED = INSTANCE_FILE.read_bytes()
INSTANCE_VALUE = yaml.safe_load(INSTANCE_SEED)


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("fuzz")


def _instance_bytes(value: Any) -> bytes:
    return yaml.safe_dump(value, allow_unicode=True).encode("utf-8")


@FUZZ
@given(
    data=st.one_of(
        byte_mutants([INSTANCE_SEED]), value_mutants(INSTANCE_VALUE).map(_instance_bytes)
    )
)
def test_instance_loader(folder: Path, data: bytes) -> None:
    path = folder / "instance.yaml"
    path.write_bytes(data)
    _only_project_errors(lambda: load_instance(path))


# -- plan JSON ---------------------------------------------------------------------------------
def _plan_seed() -> PlanFile:
    scene = load_scene()
    home = np.concatenate([np.array(a.home) for a in scene.arms])
    t = np.array([0.0, 0.05, 0.1])
    ramp = (t / t[-1])[:, None]
    first = MotionSegment(t, home + ramp * 0.1, "plain", ("o1",), "move")
    second = MotionSegment(t, first.q[-1] - ramp * 0.05, "plain", ("o1",), "move")
    grasp = GripperEvent("left", "grasp", "o1", pose_xyz_yaw(0.0, 0.0, 0.01, 0.4))
    plan = build_plan_file(
        scene,
        "T1",
        {"o1": (-0.1, 0.1, 0.3)},
        {"o1": (0.08, 0.04, 0.05)},
        [first, grasp, second],
        {"planning_time": 1.5, "actions": 2},
    )
    return plan


@pytest.fixture(scope="module")
def plan_seed(folder: Path) -> tuple[bytes, Any]:
    path = save_plan(_plan_seed(), folder / "seed.json")
    load_plan(path)  # the seed is valid
    data = path.read_bytes()
    return data, json.loads(data)


@FUZZ
@given(choice=st.data())
def test_plan_loader(folder: Path, plan_seed: tuple[bytes, Any], choice: st.DataObject) -> None:
    seed_bytes, seed_value = plan_seed
    data = choice.draw(
        st.one_of(
            byte_mutants([seed_bytes]),
            value_mutants(seed_value).map(lambda v: json.dumps(v).encode("utf-8")),
        )
    )
    path = folder / "plan.json"
    path.write_bytes(data)
    _only_project_errors(lambda: load_plan(path))
