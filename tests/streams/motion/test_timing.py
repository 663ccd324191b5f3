import warnings

import numpy as np
import pytest

from sdar_tamp.errors import ParameterError
from streams.motion import timing
from streams.motion.timing import (
    natural_spline,
    sample_limit_ratio,
    spline_curve,
    spline_eval,
    time_parameterize,
    tridiagonal_solve,
)

V = np.full(12, np.pi)
A = np.full(12, 5.0)


def _fd(t: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    dt = np.diff(t)
    vel = np.diff(q, axis=0) / dt[:, None]
    acc = np.diff(vel, axis=0) / (0.5 * (dt[1:] + dt[:-1]))[:, None]
    return vel, acc


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_limits_endpoints_and_sampling(seed: int) -> None:
    rng = np.random.default_rng(seed)
    W = np.cumsum(rng.normal(0.0, 0.2, (8, 12)), axis=0)
    traj = time_parameterize(W, V, A)
    vel, acc = _fd(traj.t, traj.q)
    assert np.abs(vel).max() <= np.pi
    assert np.abs(acc).max() <= 5.0 * 1.01
    assert np.diff(traj.t).max() <= 0.02 + 1e-12
    np.testing.assert_allclose(traj.q[0], W[0])
    np.testing.assert_allclose(traj.q[-1], W[-1])
    assert np.abs(vel[0]).max() < 0.1 and np.abs(vel[-1]).max() < 0.1  # at rest


def test_straight_line_is_a_synchronised_bang_bang_profile() -> None:
    W = np.zeros((2, 12))
    W[1, 0] = 2.0  # only joint 0 moves 2 rad
    traj = time_parameterize(W, V, A, safety=1.0, grid_step=0.002, max_grid=2000)
    # trapezoid: accelerate to pi at 5 rad/s^2 (0.987 rad), cruise, brake
    t_acc = np.pi / 5.0
    expected = 2 * t_acc + (2.0 - np.pi * t_acc) / np.pi
    assert traj.duration == pytest.approx(expected, rel=0.02)


def test_spline_interpolates_waypoints() -> None:
    s = np.array([0.0, 1.0, 2.5, 3.0])
    y = np.array([[0.0], [1.0], [0.5], [2.0]])
    M = natural_spline(s, y)
    val, _, _ = spline_eval(s, y, M, s)
    np.testing.assert_allclose(val, y, atol=1e-12)


@pytest.mark.parametrize("m", [1, 2, 3, 17, 64, 300])
def test_tridiagonal_solve_agrees_with_a_dense_solve(m: int) -> None:
    """The spline's system with uneven spacing (steps a thousand times apart), several
    right-hand sides: the same solution as a dense solve, to rounding."""
    rng = np.random.default_rng(m)
    h = rng.uniform(0.001, 1.0, m + 1)
    off, diag = h[1:-1], 2.0 * (h[:-1] + h[1:])
    rhs = rng.normal(size=(m, 5))
    dense = np.diag(diag) + np.diag(off, 1) + np.diag(off, -1)
    np.testing.assert_allclose(tridiagonal_solve(off, diag, rhs), np.linalg.solve(dense, rhs),
                               rtol=1e-9, atol=1e-12)  # fmt: skip


def test_natural_spline_has_zero_curvature_at_its_ends_and_matches_slopes() -> None:
    """Many uneven waypoints: second derivatives vanish at both ends and the first
    derivative is continuous at every interior waypoint (what the tridiagonal system asks)."""
    rng = np.random.default_rng(3)
    s = np.concatenate([[0.0], np.cumsum(rng.uniform(0.01, 0.5, 199))])
    y = np.cumsum(rng.normal(size=(200, 3)), axis=0)
    M = natural_spline(s, y)
    assert np.abs(M[[0, -1]]).max() == 0.0
    eps = 1e-9
    _, left, _ = spline_eval(s, y, M, s[1:-1] - eps)
    _, right, _ = spline_eval(s, y, M, s[1:-1] + eps)
    np.testing.assert_allclose(left, right, atol=1e-5 * max(1.0, np.abs(left).max()))


def test_single_point_is_a_zero_length_trajectory() -> None:
    traj = time_parameterize(np.ones((3, 12)), V, A)
    assert traj.duration == 0.0 and traj.q.shape == (1, 12)


def test_spline_curve_is_the_path_the_parameterisation_follows() -> None:
    a, b = np.zeros(3), np.array([1.0, -2.0, 0.5])
    line = spline_curve(np.stack([a, b]), 5)
    np.testing.assert_allclose(line, np.linspace(0.0, 1.0, 5)[:, None] * b[None], atol=1e-12)
    via = np.array([0.5, 0.0, 1.0])
    W = np.stack([a, via, b])
    curve = spline_curve(W, 101)
    np.testing.assert_allclose(curve[[0, -1]], W[[0, -1]], atol=1e-12)
    assert np.min(np.linalg.norm(curve - via, axis=1)) < 0.02  # passes through the via point
    traj = time_parameterize(W, np.ones(3), np.ones(3))
    # every timed sample lies on the curve
    dist = np.linalg.norm(traj.q[:, None] - curve[None], axis=2).min(axis=1)
    assert dist.max() < 0.03


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_full_limits_keep_every_sample_within_them(seed: int) -> None:
    rng = np.random.default_rng(seed)
    W = np.cumsum(rng.normal(0.0, 0.2, (8, 12)), axis=0)
    fast = time_parameterize(W, V, A, safety=1.0)
    rv, ra = sample_limit_ratio(fast.t, fast.q, V, A)
    assert rv <= 1.0 and ra <= 1.0  # interval velocities, second differences, ends from rest
    assert fast.duration < time_parameterize(W, V, A, safety=0.95).duration


def test_coarse_profile_is_slowed_until_the_samples_keep_the_limits() -> None:
    rng = np.random.default_rng(4)
    W = np.cumsum(rng.normal(0.0, 0.3, (6, 12)), axis=0)
    # a grid far too coarse for the curve: the profile alone would break the limits
    traj = time_parameterize(W, V, A, safety=1.0, grid_step=1.0, max_grid=8)
    rv, ra = sample_limit_ratio(traj.t, traj.q, V, A)
    assert rv <= 1.0 and ra <= 1.0


@pytest.mark.parametrize("safety", [0.0, -0.1, 1.2, float("nan")])
def test_safety_out_of_range(safety: float) -> None:
    with pytest.raises(ParameterError, match=r"safety must lie in \(0, 1\]"):
        time_parameterize(np.stack([np.zeros(12), np.ones(12)]), V, A, safety=safety)


def test_path_speed_cap_slows_the_capped_part_only() -> None:
    W = np.zeros((5, 12))
    W[:, 0] = np.linspace(0.0, 2.0, 5)
    free = time_parameterize(W, V, A, safety=1.0)
    cap = np.array([0.2, 0.2, np.inf, np.inf, np.inf])  # [rad/s] on the first half rad
    capped = time_parameterize(W, V, A, safety=1.0, path_speed=cap)
    assert capped.duration > free.duration
    vel = np.diff(capped.q[:, 0]) / np.diff(capped.t)
    first = capped.q[1:, 0] <= 0.5
    assert np.abs(vel[first]).max() <= 0.2 * 1.01
    assert np.abs(vel).max() > 1.0  # the rest is not capped


def _max_x_every_vertex(rows: np.ndarray, a2: np.ndarray, xv: float, xn: float, ds: float) -> float:
    """The backward pass's step by plain enumeration of every pair of constraint lines."""
    box = np.array([[1.0, 0.0], [-1.0, 0.0], [1.0, 2 * ds], [-1.0, -2 * ds]])
    G = np.concatenate([box, rows, -rows])
    h = np.concatenate([np.array([xv, 0.0, xn, 0.0]), a2, a2])
    best = 0.0
    for i in range(len(G)):
        for j in range(i + 1, len(G)):
            det = G[i, 0] * G[j, 1] - G[i, 1] * G[j, 0]
            if abs(det) <= 1e-12:
                continue
            x = (h[i] * G[j, 1] - G[i, 1] * h[j]) / det
            u = (G[i, 0] * h[j] - h[i] * G[j, 0]) / det
            if np.all(G @ np.array([x, u]) <= h + 1e-9):
                best = max(best, x)
    return best


@pytest.mark.parametrize("seed", [0, 1])
def test_vertex_search_matches_plain_enumeration(seed: int) -> None:
    rng = np.random.default_rng(seed)
    k, n, ds = 12, 4, 0.02
    dq = rng.normal(0.0, 0.5, (k + 1, n))
    ddq = rng.normal(0.0, 2.0, (k + 1, n))
    dq[:, 1] = 0.0  # a joint that does not move: parallel and empty rows
    ddq[:, 1] = 0.0
    a2 = np.tile(rng.uniform(2.0, 6.0, n), 2)
    rows = timing._accel_rows(dq, ddq, ds)
    xv = rng.uniform(0.5, 4.0, k)
    vertices = timing._Vertices(*timing._constraints(rows, a2, ds), xv)
    for step in range(k):
        for xn in (0.0, 0.3, 2.0, 50.0):
            expected = _max_x_every_vertex(rows[step], a2, float(xv[step]), xn, ds)
            assert vertices.max_x(step, xn) == pytest.approx(expected, rel=1e-12, abs=1e-15)


@pytest.mark.parametrize("amplitude", [0.1, 0.15, 0.25, 0.5])
def test_a_path_that_turns_back_is_timed_without_warnings(amplitude: float) -> None:
    """Out to a via configuration and back (a retreat, then the approach to the same grasp):
    where the spline's tangent vanishes (on a grid point for 0.1, 0.25 and 0.5 rad) no joint
    bounds the speed; the profile still starts, turns and ends at rest within the limits, and
    numpy raises no warning."""
    a = np.zeros(12)
    b = a.copy()
    b[1], b[2] = -amplitude, amplitude / 2
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        traj = time_parameterize(np.stack([a, b, a]), V, A)
    vel, acc = _fd(traj.t, traj.q)
    assert np.abs(vel).max() <= np.pi and np.abs(acc).max() <= 5.0 * 1.01
    np.testing.assert_allclose(traj.q[[0, -1]], np.stack([a, a]), atol=1e-12)
    turn = int(np.argmin(traj.q[:, 1]))
    assert traj.q[turn, 1] == pytest.approx(-amplitude, abs=2e-3)


def _validator_ratio(t: np.ndarray, q: np.ndarray) -> float:
    """Largest acceleration ratio as the plan validator measures it: second divided
    differences at every sample, the robot at rest one spacing before the first sample and
    after the last one (written out here, apart from the module's own check)."""
    h = np.diff(t)
    vel = np.diff(q, axis=0) / h[:, None]
    rest = np.zeros((1, q.shape[1]))
    v_ext = np.concatenate([rest, vel, rest])
    h_ext = np.concatenate([h[:1], h, h[-1:]])
    acc = np.diff(v_ext, axis=0) / (0.5 * (h_ext[1:] + h_ext[:-1]))[:, None]
    return float(np.max(np.abs(acc) / A[: q.shape[1]]))


def _there_and_back(samples: int, amplitude: float) -> np.ndarray:
    """Out to a lifted configuration and back the same way, the waypoints closing in on the
    turn (a straight retreat and the approach to the same grasp): the curve turns sharply
    there, between grid points of the speed profile."""
    d = np.zeros(12)
    d[1], d[2], d[3] = -amplitude, amplitude / 2, amplitude
    out = np.sin(np.linspace(0.0, 1.0, samples) * np.pi / 2)[:, None] * d
    return np.concatenate([out, out[::-1][1:]])


@pytest.mark.parametrize(("samples", "amplitude", "safety"),
                         [(9, 0.1, 1.0), (18, 0.2, 0.95), (18, 0.3, 0.95)])  # fmt: skip
def test_a_sharp_turn_keeps_the_limits_at_every_sample(
    samples: int, amplitude: float, safety: float
) -> None:
    """The uniform slowing of a profile through a sharp turn converges slowly (the samples
    see more of the curvature's peak as the profile slows); six rounds used to leave 0.3% to
    4% of acceleration over the limit. Every sample keeps it now, the ends from rest too."""
    traj = time_parameterize(_there_and_back(samples, amplitude), V, A, safety=safety)
    rv, ra = sample_limit_ratio(traj.t, traj.q, V, A)
    assert rv <= 1.0 and ra <= 1.0
    assert _validator_ratio(traj.t, traj.q) <= 1.0 + 1e-9


def _profile_of(W: np.ndarray, monkeypatch: pytest.MonkeyPatch) -> timing._Profile:
    """The speed profile :func:`time_parameterize` builds for ``W`` (caught on its way)."""
    seen: list[timing._Profile] = []
    sample = timing._Profile.sample

    def spy(self: timing._Profile, scale: float, dt: float) -> tuple[np.ndarray, np.ndarray]:
        seen.append(self)
        return sample(self, scale, dt)

    with monkeypatch.context() as m:
        m.setattr(timing._Profile, "sample", spy)
        time_parameterize(W, V, A, safety=1.0)
    return seen[0]


@pytest.mark.parametrize("seed", [0, 1])
def test_profile_peaks_bound_every_sampling(seed: int, monkeypatch: pytest.MonkeyPatch) -> None:
    """The peak ratio is the motion's own (sampled a hundred times denser than a plan, the
    measures come within 3% of it and never above), and time stretched by it keeps the
    limits at any sample spacing."""
    rng = np.random.default_rng(seed)
    W = np.concatenate([_there_and_back(9, 0.1), np.cumsum(rng.normal(0.0, 0.1, (5, 12)), 0)])
    profile = _profile_of(W, monkeypatch)
    peak = profile.peak_ratio(V, A)
    t, q = profile.sample(1.0, 2e-4)
    rv, ra = sample_limit_ratio(t, q, V, A)
    dense = max(rv, float(np.sqrt(ra)))
    assert 0.97 * peak <= dense <= peak
    for dt in (0.02, 0.013, 0.004):
        t, q = profile.sample(peak * (1.0 + 1e-7), dt)
        assert _validator_ratio(t, q) <= 1.0 + 1e-9


def test_quadratic_peak_inside_and_at_the_ends() -> None:
    f0, fm, f1 = (np.array([[v1, v2]]) for v1, v2 in ((1.0, 0.0), (0.0, 1.0), (1.0, 3.0)))
    # x^2 (peak 1 at the ends, 0 inside); 1 + 1.5 x + 0.5 x^2 (largest at x = 1)
    np.testing.assert_allclose(timing._quadratic_peak(f0, fm, f1), [[1.0, 3.0]])
    # -4 (x - 0.5)^2 + 1: the vertex inside, at 1
    g = lambda x: -4.0 * (x - 0.5) ** 2 + 1.0  # noqa: E731
    peak = timing._quadratic_peak(*(np.array([[g(x)]]) for x in (-1.0, 0.0, 1.0)))
    assert peak[0, 0] == pytest.approx(8.0)  # |g(-1)| = 8 beats the vertex's 1
    h = lambda x: 2.0 - (x - 0.25) ** 2  # noqa: E731
    peak = timing._quadratic_peak(*(np.array([[h(x)]]) for x in (-1.0, 0.0, 1.0)))
    assert peak[0, 0] == pytest.approx(2.0)  # the vertex at x = 0.25


def test_the_peak_slowing_ends_the_rounds(monkeypatch: pytest.MonkeyPatch) -> None:
    """Without any round of slowing, the last resort alone keeps the limits."""
    monkeypatch.setattr(timing, "_SLOWDOWN_ROUNDS", 0)
    monkeypatch.setattr(timing, "_OVERSHOOT_ROUNDS", 0)
    W = _there_and_back(9, 0.1)
    traj = time_parameterize(W, V, A, safety=1.0)
    assert _validator_ratio(traj.t, traj.q) <= 1.0 + 1e-9
    np.testing.assert_allclose(traj.q[[0, -1]], W[[0, -1]], atol=1e-12)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_pieces_joined_keep_the_limits_at_their_junctions(seed: int) -> None:
    """Rest-to-rest pieces of different sample spacings, sharp turns and single samples
    among them, joined end to start: the validator's measure holds at every junction (each
    end keeps half the limit, the two halves add up at most to the limit)."""
    rng = np.random.default_rng(seed)
    traj = time_parameterize(np.zeros((1, 12)), V, A)
    for k in range(6):
        start = traj.q[-1]
        if k % 3 == 1:
            W = start + _there_and_back(int(rng.integers(6, 20)), float(rng.uniform(0.05, 0.3)))
        elif k % 3 == 2:
            W = start[None]  # a single sample: nothing to add
        else:
            W = start + np.cumsum(rng.normal(0.0, 0.2, (4, 12)), axis=0)
            W[0] = start
        piece = time_parameterize(W, V, A, dt=float(rng.uniform(0.005, 0.02)),
                                  safety=float(rng.choice([0.95, 1.0])))  # fmt: skip
        traj = traj.then(piece)
    assert len(traj.t) > 100
    assert np.all(np.diff(traj.t) > 0.0)
    assert _validator_ratio(traj.t, traj.q) <= 1.0 + 1e-9


def test_joints_at_rest_stay_put_and_leave_the_others_timing_alone() -> None:
    """An idle arm's joints (constant waypoints) bind nothing: they stay exactly where they
    are, and the moving joints are timed as they would be alone (up to rounding)."""
    rng = np.random.default_rng(7)
    moving = np.cumsum(rng.normal(size=(9, 6)) * 0.2, axis=0)
    full = np.hstack([np.full((9, 6), 0.3), moving, np.full((9, 12), -0.7)])
    v, a = np.full(24, 3.0), np.full(24, 8.0)
    both = time_parameterize(full, v, a)
    alone = time_parameterize(moving, v[:6], a[:6])
    assert np.allclose(both.q[:, :6], 0.3, rtol=0, atol=1e-12)
    assert np.allclose(both.q[:, 12:], -0.7, rtol=0, atol=1e-12)
    assert both.duration == pytest.approx(alone.duration, rel=1e-12)
    assert both.t.shape == alone.t.shape and np.allclose(both.t, alone.t, rtol=0, atol=1e-12)
    assert np.allclose(both.q[:, 6:12], alone.q, rtol=0, atol=1e-12)
