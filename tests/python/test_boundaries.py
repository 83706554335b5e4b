"""Every entry point of the Python module against random shapes, dtypes, NaN and inf (issue #40).

Property: a call either returns (converged results finite) or raises ValueError naming what is
wrong; never another exception, a crash or a read outside an array (make check-sanitize runs
this file under AddressSanitizer). Hypothesis (Debian python3-hypothesis) draws the inputs; the
example counts keep the file under a minute. Plus the issue's three reproductions: evaluate()
read outside its input, MechanicalSystem(-M, C, K) was accepted, run_scene(dict) took neither
numpy values nor a NaN with its key.
"""
import math
import os

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

import wbm

# make test draws the same examples on every run (derandomize: a test that passes does not flip);
# WBM_HYPOTHESIS_EXAMPLES=2000 hunts longer, with fresh random draws.
HUNT = "WBM_HYPOTHESIS_EXAMPLES" in os.environ
EXAMPLES = int(os.environ.get("WBM_HYPOTHESIS_EXAMPLES", "60"))
QUIET = [HealthCheck.too_slow, HealthCheck.data_too_large, HealthCheck.filter_too_much]
SETTINGS = settings(max_examples=EXAMPLES, deadline=None, derandomize=not HUNT, suppress_health_check=QUIET)
FEW = settings(max_examples=max(EXAMPLES // 3, 10), deadline=None, derandomize=not HUNT, suppress_health_check=QUIET)

REALS = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True, width=64),
    st.sampled_from([0.0, -1.0, 1.0, 1e-300, 1e300, -1e300, math.nan, math.inf, -math.inf]),
)
NUMERIC_DTYPES = st.sampled_from([np.float64, np.float32, np.int64, np.int8, np.bool_, np.uint16])
ODD_DTYPES = st.sampled_from([np.complex128, "<U3", object])


@st.composite
def arrays(draw, max_dims=3, side=4):
    """Arrays of 0 … max_dims dimensions with sides 0 … side: numeric (NaN and inf included for
    floats) or of a dtype that holds no real numbers (complex, str, object)."""
    shape = draw(hnp.array_shapes(min_dims=0, max_dims=max_dims, min_side=0, max_side=side))
    if draw(st.integers(0, 5)) == 0:
        dtype = draw(ODD_DTYPES)
        if dtype is object:
            return np.full(shape, None, dtype=object)
        if dtype == "<U3":
            return np.full(shape, "abc")
        return np.full(shape, 1 + 2j)
    dtype = np.dtype(draw(NUMERIC_DTYPES))
    elements = REALS.filter(math.isfinite) if dtype.kind != "f" else st.floats(width=32 if dtype == np.float32 else 64)
    if dtype.kind in "iub":
        elements = None
    return draw(hnp.arrays(dtype, shape, elements=elements))


def square(n, scale=1.0):
    return scale * np.eye(n)


def allowed(call):
    """Runs call(); returns its value, None for ValueError; any other exception fails the test."""
    try:
        return call()
    except ValueError as e:
        assert str(e), "a ValueError must say what is wrong"
        return None


def finite_arrays(result):
    for v in result.values():
        if isinstance(v, np.ndarray) and v.dtype.kind == "f":
            assert np.isfinite(v).all()


# --- the reproductions -------------------------------------------------------------

def test_evaluate_refuses_coefficients_of_another_width_instead_of_reading_past_them():
    with pytest.raises(ValueError, match=r"coefficients has shape \(1, 1\); expected \(n, M\) = \(n, 64\)"):
        wbm.evaluate(wbm.TimeBasis("fourier", 64), np.ones((1, 1)), np.array([0.0, 0.25]))
    with pytest.raises(ValueError, match=r"\(n, M\) = \(n, 8\)"):
        wbm.evaluate(wbm.TimeBasis("haar", 8), np.ones((1, 4)), np.array([0.1]))
    # The right width gives Σ_k a_k v_k(τ): Fourier M = 3 is {1, cos 2πτ, sin 2πτ}.
    tau = np.array([0.0, 0.25, 0.6])
    u = wbm.evaluate(wbm.TimeBasis("fourier", 3), np.array([[1.0, 2.0, 3.0]]), tau)
    exact = 1 + 2 * np.cos(2 * np.pi * tau) + 3 * np.sin(2 * np.pi * tau)
    assert u.shape == (1, 3) and np.allclose(u[0], exact, rtol=0, atol=1e-14)


def test_a_negative_mass_or_stiffness_is_refused_rigid_body_modes_are_not():
    m, c, k = np.diag([1.0, 2.0]), np.zeros((2, 2)), np.array([[3e4, -1e4], [-1e4, 2e4]])
    with pytest.raises(ValueError, match="M is not positive definite"):
        wbm.MechanicalSystem(-m, c, k)
    with pytest.raises(ValueError, match="K is not positive semidefinite: .* has 1 eigenvalue"):
        wbm.MechanicalSystem(m, c, np.array([[3e4, -1e4], [-1e4, -2e4]]))
    free = wbm.MechanicalSystem(m, c, np.array([[1e4, -1e4], [-1e4, 1e4]]))  # two masses on one spring
    f = wbm.natural_frequencies_hz(free)
    assert f[0] == pytest.approx(0.0, abs=1e-6)
    assert f[1] == pytest.approx(math.sqrt(1e4 * (1.0 + 0.5)) / (2 * math.pi), rel=1e-12)  # ω² = k (1/m1 + 1/m2)


def test_scene_dicts_take_numpy_values_and_name_the_key_of_a_nan():
    oscillator = {"structure": {"mass": np.array([1.0]), "stiffness": [np.float64(4e4)]},
                  "damping": {"alpha": np.float32(5.0)},
                  "forcing": {"amplitude": np.int64(2), "frequency_hz": 10.0}}
    r = wbm.run_scene(oscillator)
    assert r["converged"]
    w = 2 * math.pi * 10.0
    amplitude = 2.0 / abs(complex(4e4 - w * w, 5.0 * w))
    u = r["tables"]["displacement.csv"]
    key = next(h for h in u if h.startswith("u_"))
    assert np.max(np.abs(u[key])) == pytest.approx(amplitude, rel=1e-5)  # sampled peak: 1 − cos(π/P) below
    oscillator["forcing"]["frequency_hz"] = np.float64(math.nan)
    with pytest.raises(ValueError, match="key 'forcing.frequency_hz' is nan"):
        wbm.run_scene(oscillator)
    with pytest.raises(ValueError, match=r"key 'structure.mass\[0\]' is inf"):
        wbm.run_scene({"structure": {"mass": [math.inf], "stiffness": [1.0]}})


# --- properties over every entry point -----------------------------------------------------

@SETTINGS
@given(name=st.sampled_from(["fourier", "haar", "db6", "bspline", "db7", "x"]), m=st.integers(-4, 70),
       tau=arrays(max_dims=2, side=5), derivative=st.integers(-2, 3))
def test_time_basis_values(name, m, tau, derivative):
    basis = allowed(lambda: wbm.TimeBasis(name, m))
    if basis is None:
        return
    v = allowed(lambda: basis.values(tau, derivative))
    if v is not None:
        assert v.shape == (np.asarray(tau).size, m) and np.isfinite(v).all()


@SETTINGS
@given(name=st.sampled_from(["fourier", "haar", "db6", "bspline"]), level=st.integers(0, 5),
       coefficients=arrays(max_dims=3, side=40), tau=arrays(max_dims=2, side=5))
def test_evaluate(name, level, coefficients, tau):
    basis = allowed(lambda: wbm.TimeBasis(name, 2 ** level))
    if basis is None:
        return
    u = allowed(lambda: wbm.evaluate(basis, coefficients, tau))
    if u is not None:
        assert u.shape == (np.asarray(coefficients).shape[0], np.asarray(tau).size) and np.isfinite(u).all()


@SETTINGS
@given(mass=arrays(side=3), damping=arrays(side=3), stiffness=arrays(side=3))
def test_mechanical_system(mass, damping, stiffness):
    s = allowed(lambda: wbm.MechanicalSystem(mass, damping, stiffness))
    if s is not None:
        assert np.isfinite(wbm.natural_frequencies_hz(s)).all()


@SETTINGS
@given(values=st.lists(REALS, min_size=5, max_size=5), elements=st.integers(-2, 30), beta=REALS)
def test_rod(values, elements, beta):
    e, rho, area, length, _ = values
    rod = allowed(lambda: wbm.rod(e, rho, area, length, elements, beta))
    if rod is not None:
        assert rod.dofs == elements


@SETTINGS
@given(family=st.sampled_from(["haar", "db4", "db6", "db5", "bspline", "db40", "dbx"]), d1=st.integers(-1, 4),
       d2=st.integers(-1, 4))
def test_connection_coefficients(family, d1, d2):
    g = allowed(lambda: wbm.connection_coefficients(family, d1, d2))
    if g is not None:
        assert np.isfinite(g["values"]).all()


@SETTINGS
@given(a=REALS, b=REALS, gap=REALS, u=REALS)
def test_contact_laws(a, b, gap, u):
    for make in (lambda: wbm.ExponentialPenalty(a, b, gap), lambda: wbm.LinearPenalty(a, gap),
                 lambda: wbm.RigidStop(gap)):
        law = allowed(make)
        if law is None or law.rigid:
            continue
        force = allowed(lambda: law.force(u))
        if force is not None:
            assert force >= 0.0 and not math.isnan(force)


SYSTEM = wbm.MechanicalSystem(np.diag([1.0, 2.0]), np.diag([3.0, 1.5]), np.array([[3e4, -1e4], [-1e4, 2e4]]))


@SETTINGS
@given(dof=st.integers(-2, 3), amplitude=REALS, frequency=REALS, gap=REALS,
       trial=st.sampled_from([("fourier", 9), ("bspline", 16), ("haar", 16)]),
       formulation=st.sampled_from(["distributional", "weak", "strong", "other"]),
       load=st.tuples(st.integers(-1, 2), REALS, REALS, st.integers(-1, 12)),
       harmonics=st.lists(st.integers(-1, 6), max_size=3))
def test_solve(dof, amplitude, frequency, gap, trial, formulation, load, harmonics):
    law = allowed(lambda: wbm.LinearPenalty(1e5, gap))
    if law is None:
        return
    basis = wbm.TimeBasis(*trial)
    weighting = wbm.TimeBasis("fourier", trial[1]) if trial[0] == "haar" else basis
    r = allowed(lambda: wbm.solve(SYSTEM, dof, amplitude, frequency, [(1, law)], basis, weighting, formulation,
                                  [load], harmonics))
    if r is not None and r["converged"]:
        # the verified quantity is the backward error; it never exceeds the relative residual
        assert np.isfinite(r["coefficients"]).all() and r["backward_error"] <= r["residual_tolerance"]
        assert r["backward_error"] <= r["relative_residual"]


@FEW
@given(frequency=st.tuples(REALS, REALS), max_step=REALS, max_points=st.integers(-1, 40),
       samples=st.integers(-1, 64), stability=st.booleans())
def test_trace_response(frequency, max_step, max_points, samples, stability):
    law = wbm.LinearPenalty(1e5, 1e-3)
    basis = wbm.TimeBasis("fourier", 7)
    r = allowed(lambda: wbm.trace_response(SYSTEM, 0, 50.0, frequency, [(1, law)], basis, basis,
                                           stability=stability, max_step=max_step, max_points=max_points,
                                           samples=samples))
    if r is not None:
        assert np.isfinite(r["frequency_hz"]).all() and np.isfinite(r["max_displacement"]).all()


@FEW
@given(dof=st.integers(-1, 2), gap=REALS, energy=st.tuples(REALS, REALS), harmonics=st.integers(-1, 6),
       samples=st.integers(-1, 40), penalty=REALS, step=REALS)
def test_nonlinear_mode(dof, gap, energy, harmonics, samples, penalty, step):
    undamped = wbm.MechanicalSystem(np.diag([1.0, 2.0]), np.zeros((2, 2)), np.array([[3e4, -1e4], [-1e4, 2e4]]))
    e = (min(max(energy[0], -1.0), 3.0) if math.isfinite(energy[0]) else energy[0],
         min(max(energy[1], -1.0), 3.0) if math.isfinite(energy[1]) else energy[1])  # a short branch: seconds
    r = allowed(lambda: wbm.nonlinear_mode(undamped, [(dof, gap)], e, harmonics, samples, penalty,
                                           max(step, 1e-2) if math.isfinite(step) else step))
    if r is not None:
        assert np.isfinite(r["energy"]).all() and np.isfinite(r["frequency_hz"]).all()


@FEW
@given(mass=REALS, stiffness=REALS, amplitude=REALS, frequency=REALS, gap=REALS, e=REALS,
       cells=st.integers(-2, 600), dof=st.integers(-1, 2))
def test_haar_impact(mass, stiffness, amplitude, frequency, gap, e, cells, dof):
    def system():
        return wbm.MechanicalSystem(np.array([[mass]]), np.array([[0.1]]), np.array([[stiffness]]))
    s = allowed(system)
    if s is None:
        return
    r = allowed(lambda: wbm.haar_impact(s, 0, amplitude, frequency, [(dof, gap)], e, cells, [], 3))
    if r is not None:
        finite_arrays(r)
        for key in ("residual", "complementarity", "penetration", "reference_displacement"):
            assert math.isfinite(r[key]), key


@FEW
@given(name=st.sampled_from(["fourier", "bspline", "db6", "db4", "haar"]), level=st.integers(0, 6),
       energy=st.tuples(REALS, REALS), samples=st.integers(-1, 80), offset=st.one_of(st.none(), REALS),
       step=REALS)
def test_basis_mode(name, level, energy, samples, offset, step):
    undamped = wbm.MechanicalSystem(np.diag([1.0, 2.0]), np.zeros((2, 2)), np.array([[3e4, -1e4], [-1e4, 2e4]]))
    e = (min(max(energy[0], -1.0), 0.9) if math.isfinite(energy[0]) else energy[0],
         min(max(energy[1], -1.0), 1.5) if math.isfinite(energy[1]) else energy[1])  # a short branch
    r = allowed(lambda: wbm.basis_mode(undamped, [(1, 1e-3)], e, wbm.TimeBasis(name, 2 ** level), samples, offset,
                                       max(step, 2e-2) if math.isfinite(step) else step))
    if r is not None:
        finite_arrays(r)


SCENE_VALUES = st.one_of(REALS, st.integers(-10, 10), st.text(max_size=4), st.booleans(), st.none(),
                         arrays(max_dims=1, side=3), st.lists(REALS, max_size=3))


@SETTINGS
@given(mass=SCENE_VALUES, stiffness=SCENE_VALUES, amplitude=SCENE_VALUES, frequency=SCENE_VALUES,
       extra=st.dictionaries(st.sampled_from(["basis", "output", "analysis", "nonsense"]),
                             st.dictionaries(st.sampled_from(["harmonics", "samples", "type", "dimension"]),
                                             SCENE_VALUES, max_size=2), max_size=2))
def test_run_scene_dicts(mass, stiffness, amplitude, frequency, extra):
    scene = {"structure": {"mass": mass, "stiffness": stiffness},
             "forcing": {"amplitude": amplitude, "frequency_hz": frequency}, **extra}
    if allowed(lambda: wbm.scene_json(scene)) is None:
        return
    r = allowed(lambda: wbm.run_scene(scene))
    if r is not None and r["converged"]:
        for table in r["tables"].values():
            for column in table.values():
                if isinstance(column, np.ndarray) and column.dtype.kind == "f":
                    assert np.isfinite(column).all()
