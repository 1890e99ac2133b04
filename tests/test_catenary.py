"""Irvine's elastic catenary (``pipeline.model.catenary``, issue 55 item 2).

Oracles, none of them the module's closed form: the cable's equilibrium integrated as an ODE
(scipy's solve_ivp on the tension vector and the position, written here), the inextensible
catenary's cosh shape and its textbook sag and length, and the straight elastic cable."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from pipeline.model.catenary import GIVEN, MAX_ITERATIONS, point, solve


def integrated(horizontal, vertical, length, weight, ea, samples=None):
    """The cable's end (x, z) (or its points at ``samples`` of s) from its equilibrium: the tension
    vector (H, V + w s) along its tangent, each piece ds of it stretched to (1 + T/EA) ds."""
    def slope(s, state):
        force = np.array([horizontal, vertical + weight * s])
        tension = np.hypot(*force)
        return force / tension * (1.0 + tension / ea)

    found = solve_ivp(slope, (0.0, length), [0.0, 0.0], rtol=1e-12, atol=1e-13, method="DOP853",
                      t_eval=samples)
    return found.y if samples is not None else found.y[:, -1]


def random_cables(n, seed):
    rng = np.random.default_rng(seed)
    span, rise = rng.uniform(0.2, 20, n), rng.uniform(-15, 15, n)
    weight = rng.uniform(0.01, 5, n)
    ea = np.where(rng.random(n) < 0.3, np.inf, rng.uniform(1e4, 1e7, n))
    tau = rng.uniform(1.0, 50.0, n) * weight * np.hypot(span, rise)
    return span, rise, weight, ea, tau


def test_the_closed_form_is_the_integrated_equilibrium():
    """The end and interior points of :func:`point` against the ODE, for cables with a low point
    inside and without, elastic and inextensible, light and heavy (rtol 1e-9 of the length)."""
    rng = np.random.default_rng(5)
    for _ in range(40):
        h, v = rng.uniform(1, 500), rng.uniform(-300, 300)
        length, weight = rng.uniform(0.5, 30), rng.uniform(0.0, 20)
        ea = rng.choice([np.inf, rng.uniform(1e3, 1e7)])
        s = np.linspace(0.0, length, 7)
        exact = integrated(h, v, length, weight, ea, s)
        x, z = point(h, v, s, weight, ea)
        assert np.allclose(x, exact[0], atol=1e-9 * length) and np.allclose(z, exact[1], atol=1e-9 * length)


def test_the_inextensible_cable_is_a_cosh_with_the_textbook_sag_and_length():
    """A level cable of span a under H: length 2c sinh(a/2c), sag c (cosh(a/2c) - 1), c = H/w, and
    every point on z = c (cosh((x - a/2)/c) - cosh(a/2c)) (Irvine 1981, eqs. 1.9-1.11)."""
    h, w, a = 20.0, 1.5, 12.0
    c = h / w
    cable = solve(a, 0.0, w, np.inf, "chord_tension", h)
    assert cable.converged
    assert cable.length == pytest.approx(2 * c * np.sinh(a / (2 * c)), rel=1e-12)
    assert cable.sag == pytest.approx(c * (np.cosh(a / (2 * c)) - 1), rel=1e-10)
    assert cable.vertical == pytest.approx(-w * cable.length / 2, rel=1e-12)
    x, z = point(cable.horizontal, cable.vertical, np.linspace(0, cable.length, 9), w, np.inf)
    assert np.allclose(z, c * (np.cosh((x - a / 2) / c) - np.cosh(a / (2 * c))), atol=1e-12 * a)


@pytest.mark.parametrize("given", GIVEN)
def test_every_solved_cable_meets_its_ends(given):
    """From each kind of condition, the solved cable, integrated from end A as an ODE, reaches
    end B (1e-8 of the chord), and meets its condition; 20 000 random cables converge."""
    span, rise, weight, ea, tau = random_cables(20000, 3)
    reference = solve(span, rise, weight, ea, "chord_tension", tau)
    value = {"length": reference.length, "chord_tension": tau, "top_tension": reference.top_tension,
             "sag_ratio": reference.sag / reference.chord}[given]
    cable = solve(span, rise, weight, ea, given, value)
    assert cable.converged.all()
    got = {"length": cable.length, "chord_tension": cable.chord_tension, "top_tension": cable.top_tension,
           "sag_ratio": cable.sag / cable.chord}[given]
    assert np.allclose(got, value, rtol=1e-9, atol=1e-12)
    for k in range(0, 20000, 997):
        end = integrated(cable.horizontal[k], cable.vertical[k], cable.length[k], weight[k], ea[k])
        assert np.allclose(end, [span[k], rise[k]], atol=1e-8 * cable.chord[k])


def test_the_largest_tension_and_the_sag_are_the_integrated_cables():
    """The top tension is the largest |T(s)| along the cable and the sag the largest distance of
    its integrated points from the chord (1e-6 of the chord: 20 001 samples)."""
    span, rise, weight, ea, tau = random_cables(12, 8)
    cable = solve(span, rise, weight, ea, "chord_tension", tau)
    for k in range(12):
        s = np.linspace(0.0, cable.length[k], 20001)
        x, z = integrated(cable.horizontal[k], cable.vertical[k], cable.length[k], weight[k], ea[k], s)
        tension = np.hypot(cable.horizontal[k], cable.vertical[k] + weight[k] * s)
        assert cable.top_tension[k] == pytest.approx(tension.max(), rel=1e-12)
        below = (x * rise[k] - z * span[k]) / cable.chord[k]
        assert cable.sag[k] == pytest.approx(below.max(), abs=1e-6 * cable.chord[k])


@pytest.mark.parametrize("span", [0.0, 1e-12, 1e-8, 1e-4])
def test_nearly_vertical_cables_converge_to_the_vertical_one(span):
    """Where H -> 0 the asinh form degenerates; the solver meets the ends and its forces tend to
    the vertical cable's: V at the foot tau-like, the top carrying the cable's weight more."""
    w, ea, rise = 2.0, 1e6, 10.0
    cable = solve(span, rise, w, ea, "top_tension", 300.0)
    assert cable.converged
    assert cable.top_tension == pytest.approx(300.0, rel=1e-12)
    assert cable.vertical + w * cable.length == pytest.approx(np.sqrt(300.0 ** 2 - cable.horizontal ** 2), rel=1e-12)
    foot = 300.0 - w * cable.length  # the vertical cable: T(s) = T_A + w s
    assert cable.vertical == pytest.approx(foot, rel=1e-6)
    end = integrated(cable.horizontal, cable.vertical, cable.length, w, ea)
    assert np.allclose(end, [span, rise], atol=1e-9 * rise)


@pytest.mark.parametrize("rise", [0.0, 1e-12, -1e-9, 1e-6])
def test_nearly_level_cables(rise):
    """A level cable has its low point mid-span (the two asinh terms add); it converges from both
    sides of level and its sag is the textbook one within the rise's effect."""
    w, a, tau = 1.0, 10.0, 50.0
    cable = solve(a, rise, w, np.inf, "chord_tension", tau)
    assert cable.converged
    c = cable.horizontal / w
    assert cable.sag == pytest.approx(c * (np.cosh(a / (2 * c)) - 1), rel=1e-5)
    assert np.allclose(integrated(cable.horizontal, cable.vertical, cable.length, w, np.inf), [a, rise], atol=1e-9 * a)


def test_a_weightless_cable_is_the_straight_elastic_one():
    """w = 0: H = tau a / l, V = tau h / l, L0 = l / (1 + tau / EA), no sag (rtol 1e-12)."""
    span, rise, _, ea, tau = random_cables(500, 11)
    ea = np.where(np.isinf(ea), 1e6, ea)
    cable = solve(span, rise, 0.0, ea, "chord_tension", tau)
    chord = np.hypot(span, rise)
    assert cable.converged.all()
    assert np.allclose(cable.horizontal, tau * span / chord, rtol=1e-12)
    assert np.allclose(cable.vertical, tau * rise / chord, rtol=1e-12, atol=1e-12 * tau)
    assert np.allclose(cable.length, chord / (1 + tau / ea), rtol=1e-12)
    assert (cable.sag == 0).all()


def test_a_light_cable_tends_to_the_straight_one():
    """w -> 0: the forces tend to the straight cable's linearly in w (the weight's half at each
    end: V = tau h / l - w L0 / 2 + O(w^2))."""
    span, rise, tau = 6.0, 3.0, 100.0
    chord = np.hypot(span, rise)
    for w in (1e-2, 1e-4, 1e-6):
        cable = solve(span, rise, w, np.inf, "chord_tension", tau)
        assert cable.vertical == pytest.approx(tau * rise / chord - w * cable.length / 2, abs=10 * w ** 2 * chord)


def test_no_catenary_is_refused_not_invented():
    """A top tension below what the cable's own weight needs has no catenary: not converged; an
    unknown condition is a ValueError."""
    cable = solve(1.0, 10.0, 5.0, np.inf, "top_tension", 20.0)  # 50 N of cable hangs from the top
    assert not cable.converged
    with pytest.raises(ValueError, match="given="):
        solve(1.0, 1.0, 1.0, np.inf, "force", 1.0)
    assert MAX_ITERATIONS <= 100
