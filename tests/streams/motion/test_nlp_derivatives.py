"""The optimiser's derivatives, assembled from one knot's and mapped over the knots, are those
of the whole NLP: the Jacobian against central finite differences, the Hessian of the
Lagrangian against CasADi's own differentiation of the whole horizon."""

from __future__ import annotations

import numpy as np

from streams.motion._casadi import ca, to_array
from streams.motion.planner import MotionPlanner


def _point(planner: MotionPlanner, seed: int) -> tuple[np.ndarray, np.ndarray]:
    opt = planner.trajopt
    rng = np.random.default_rng(seed)
    n_x = int(opt._nlp["x"].shape[0])
    x = rng.uniform(-2.0, 2.0, n_x)
    p = rng.uniform(-0.5, 0.5, opt._lay.size)  # any parameters: the identities hold for all
    return x, p


def test_jacobian_matches_finite_differences(planner: MotionPlanner) -> None:
    opt = planner.trajopt
    x, p = _point(planner, 0)
    g, J = (to_array(v) for v in opt._jac_g(x, p))
    assert np.allclose(g.reshape(-1), to_array(opt._g_fn(x, p)).reshape(-1))
    h = 1e-6
    cols = np.random.default_rng(1).choice(len(x), 12, replace=False)
    for j in cols:
        e = np.zeros_like(x)
        e[j] = h
        fd = (to_array(opt._g_fn(x + e, p)) - to_array(opt._g_fn(x - e, p))).reshape(-1) / (2 * h)
        assert np.allclose(J[:, j], fd, rtol=1e-5, atol=1e-6), f"column {j}"


def test_hessian_matches_the_whole_horizon(planner: MotionPlanner) -> None:
    opt = planner.trajopt
    nlp = opt._nlp
    x, p = _point(planner, 2)
    n_g = int(nlp["g"].shape[0])
    lam_g = np.random.default_rng(3).uniform(-1.0, 1.0, n_g)
    lam_f = 0.7
    lf, lg = ca.MX.sym("lf"), ca.MX.sym("lg", n_g)
    lagrangian = lf * nlp["f"] + ca.dot(lg, nlp["g"])
    reference = ca.Function(
        "reference", [nlp["x"], nlp["p"], lf, lg], [ca.triu(ca.hessian(lagrangian, nlp["x"])[0])]
    )
    H = to_array(opt._hess_lag(x, p, lam_f, lam_g))
    H_ref = to_array(reference(x, p, lam_f, lam_g))
    assert np.abs(H_ref).max() > 1.0  # the constraint terms are in it
    assert np.allclose(H, H_ref, rtol=1e-9, atol=1e-9)
    assert np.allclose(H, np.triu(H))  # IPOPT reads the upper triangle
