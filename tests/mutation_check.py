"""Term-by-term mutation check: every physical term, its sign flipped, must fail the tests.

For each mutation below (one term of the planar, out-of-plane or 3-D model, its sign
flipped or its factor dropped) the check copies the repository, applies the mutation to
the copy, runs the default test suite's files that guard that model (stopping at the
first failure) and records whether the mutation was killed and by which test.  A
mutation that survives is a term whose sign no test can see.

Usage::

    python tests/mutation_check.py            # the table; exit 1 if a mutation survives
    python tests/mutation_check.py --json     # {"mutations": [...], "survivors": N, ...}
    python tests/mutation_check.py --only 3d  # the mutations whose model or term match
    python tests/mutation_check.py --list     # the mutations, without running them

It runs the copies with ``PYTHONPATH`` set to them, so it needs the package's
dependencies and the test extra installed (as after the README's test command) and a
default test suite that passes unmutated (CI runs it first).  Each mutation's snippet
must occur exactly once in its file: an edit of a term that moves its snippet fails the
check loudly instead of silently testing nothing.
"""

from __future__ import annotations

import argparse
import json
import os
import queue
import re
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import asdict, dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: The guards of each model, fastest killers first (pytest stops at the first failure).
PLANAR = (
    "tests/test_operators.py",
    "tests/test_batched.py",
    "tests/test_variants.py",
    "tests/test_classical.py",
    "tests/test_dynamics.py",
    "tests/test_static.py",
    "tests/test_stability.py",
    "tests/test_hysteretic.py",
)
OUT_OF_PLANE = (
    "tests/test_spatial.py",
    "tests/test_out_of_plane_guards.py",
    "tests/test_out_of_plane_strong.py",
    "tests/test_out_of_plane_motion.py",
    "tests/test_space_guards.py",
    "tests/test_space.py",
    "tests/test_hysteretic.py",
)
SPACE = (
    "tests/test_space_guards.py",
    "tests/test_space.py",
    "tests/test_out_of_plane_guards.py",
    "tests/test_space_speed.py",
    "tests/test_out_of_plane_motion.py",
    "tests/test_space_onset.py",
    "tests/test_space_motion.py",
    "tests/test_space_whirl.py",
)

#: Seconds one mutation's test run may take; past that it counts as killed (a hang).
TIMEOUT = 600.0


@dataclass(frozen=True)
class Mutation:
    """One change of one term: ``old`` replaced by ``new`` in ``path``."""

    model: str  # "planar", "out_of_plane" or "3d"
    term: str
    change: str  # "flip sign", "drop factor 2", ...
    path: str
    old: str
    new: str
    tests: tuple[str, ...]


def _m(model, term, change, path, old, new):
    tests = {"planar": PLANAR, "out_of_plane": OUT_OF_PLANE, "3d": SPACE}[model]
    return Mutation(model, term, change, f"fempipe/{path}", old, new, tests)


LT, NT, VT = (
    "model/plane/local_terms.py",
    "model/plane/nonlocal_terms.py",
    "model/plane/variants.py",
)
OP, BT, SP = "model/plane/operators.py", "model/plane/batched.py", "model/three_d/model.py"
OOP, OM = "model/out_of_plane/model.py", "model/out_of_plane/motion.py"
FLIP = "flip sign"
#: The unsteady flow out of the plane: a forced orbit's multipliers against the straight pipe's.
BENT = "tests/test_parametric.py::test_the_bent_pipe_tends_to_the_straight_one"

MUTATIONS = (
    # ------------------------------------------------------------ planar: residual --
    _m("planar", "inertia", FLIP, NT,
       "return self._project(self.quad.cumulative(fl.theta_ddot",
       "return -self._project(self.quad.cumulative(fl.theta_ddot"),
    _m("planar", "centripetal", FLIP, NT,
       "return self._project(-self.quad.cumulative(fl.theta_dot[:, None] ** 2",
       "return self._project(self.quad.cumulative(fl.theta_dot[:, None] ** 2"),
    _m("planar", "coriolis", FLIP, NT,
       "return 2.0 * p.v * np.sqrt(p.beta) * self._project(",
       "return -2.0 * p.v * np.sqrt(p.beta) * self._project("),
    _m("planar", "coriolis", "drop factor 2", NT,
       "return 2.0 * p.v * np.sqrt(p.beta) * self._project(",
       "return p.v * np.sqrt(p.beta) * self._project("),
    _m("planar", "flow_acceleration", FLIP, NT,
       "return v_dot * np.sqrt(self.params.beta) * self._project(",
       "return -v_dot * np.sqrt(self.params.beta) * self._project("),
    _m("planar", "flow_acceleration", "drop factor sqrt(beta)", NT,
       "return v_dot * np.sqrt(self.params.beta) * self._project(",
       "return v_dot * self._project("),
    _m("planar", "follower", FLIP, LT,
       "self._test(np.sin(fl.theta_tip - fl.theta))",
       "self._test(np.sin(fl.theta - fl.theta_tip))"),
    _m("planar", "gravity", FLIP, LT,
       "return p.gamma * self._test((1.0 - self.x) * np.sin(",
       "return -p.gamma * self._test((1.0 - self.x) * np.sin("),
    _m("planar", "kelvin_voigt", FLIP, LT,
       "return self.params.mu * np.asarray(self.disc.K @ qdot)",
       "return -self.params.mu * np.asarray(self.disc.K @ qdot)"),
    _m("planar", "end_mass_gravity", FLIP, VT,
       "return p.gamma * p.end_mass * self._test(",
       "return -p.gamma * p.end_mass * self._test("),
    _m("planar", "end_mass_inertia", FLIP, VT,
       "return G * (self._end_vector(fl) @ acc)",
       "return -G * (self._end_vector(fl) @ acc)"),
    _m("planar", "external_damping", FLIP, VT,
       "return sigma * self._project(",
       "return -sigma * self._project("),
    _m("planar", "spring", FLIP, "model/plane/springs.py",
       "r = r + kappa * (b @ d)",
       "r = r - kappa * (b @ d)"),
    # ----------------------------------------------------------- planar: Jacobians --
    _m("planar", "coriolis (dR/dq')", FLIP, OP,
       "dFd = dFd + self._phi_field(cv * nrm)",
       "dFd = dFd - self._phi_field(cv * nrm)"),
    _m("planar", "kelvin_voigt (dR/dq')", FLIP, OP,
       "Jqd = p.mu * self._K_dense + self._project_jac(dFd, fl)",
       "Jqd = -p.mu * self._K_dense + self._project_jac(dFd, fl)"),
    _m("planar", "external_damping (dR/dq')", FLIP, OP,
       "Jqd = Jqd + sigma * M_pipe",
       "Jqd = Jqd - sigma * M_pipe"),
    _m("planar", "coriolis (C^d)", FLIP, OP,
       "self._project_jac(self._phi_field(cv * fl.normal), fl)",
       "self._project_jac(self._phi_field(-cv * fl.normal), fl)"),
    _m("planar", "external_damping (C^d)", FLIP, OP,
       "Jqd = Jqd + p.external_damping * M_pipe",
       "Jqd = Jqd - p.external_damping * M_pipe"),
    _m("planar", "kelvin_voigt (C^d)", FLIP, OP,
       "Jqd = p.mu * self._K_dense + self._project_jac(self._phi_field(",
       "Jqd = -p.mu * self._K_dense + self._project_jac(self._phi_field("),
    _m("planar", "end_mass_inertia (M^d)", FLIP, OP,
       "M = M + p.end_mass * (b @ b.T)",
       "M = M - p.end_mass * (b @ b.T)"),
    _m("planar", "hysteretic", FLIP, "analyses/stability/hysteretic.py",
       "quadratic_eigen(K + 1j * nxt * Kb, C, M, method)",
       "quadratic_eigen(K - 1j * nxt * Kb, C, M, method)"),
    # ------------------------------------------ planar: the batched stage kernels --
    _m("planar", "coriolis (stage kernels)", FLIP, BT,
       "F = F + self._cv * th_d[:, None] * nrm",
       "F = F - self._cv * th_d[:, None] * nrm"),
    _m("planar", "kelvin_voigt (stage kernels)", FLIP, BT,
       "K @ (Q + self._mu * P).T",
       "K @ (Q - self._mu * P).T"),
    _m("planar", "follower (stage kernels)", FLIP, BT,
       "+ self._v2 * np.sin(",
       "- self._v2 * np.sin("),
    _m("planar", "gravity (stage kernels)", FLIP, BT,
       "local = self._lever * np.sin(th + self._alpha)",
       "local = -self._lever * np.sin(th + self._alpha)"),
    _m("planar", "coriolis (stage Jacobians)", FLIP, BT,
       "b, bd = -cv * th_d[:, None] * t, cv * nrm",
       "b, bd = -cv * th_d[:, None] * t, -cv * nrm"),
    _m("planar", "kelvin_voigt (stage Jacobians)", FLIP, BT,
       "Jqd = self._mu * K[None] + proj[S:]",
       "Jqd = -self._mu * K[None] + proj[S:]"),
    # ------------------------------------------- out of the plane, static state --
    _m("out_of_plane", "bending (curvature softening)", FLIP, OOP,
       'return self.fixed()["K"] - self.weighted_gram(st.dtheta**2)',
       'return self.fixed()["K"] + self.weighted_gram(st.dtheta**2)'),
    _m("out_of_plane", "gravity (axial force)", FLIP, OOP,
       "grav = p.gamma * (1.0 - self.x + p.end_mass) * np.cos(",
       "grav = -p.gamma * (1.0 - self.x + p.end_mass) * np.cos("),
    _m("out_of_plane", "end mass gravity (axial force)", "drop end mass", OOP,
       "grav = p.gamma * (1.0 - self.x + p.end_mass) * np.cos(",
       "grav = p.gamma * (1.0 - self.x) * np.cos("),
    _m("out_of_plane", "follower (axial force)", FLIP, OOP,
       "jet = v2 * 2.0 * np.sin(",
       "jet = -v2 * 2.0 * np.sin("),
    _m("out_of_plane", "follower", FLIP, OOP,
       'return v2 * (np.outer(f["integral"], self.disc.tip) - f["gram"])',
       'return -v2 * (np.outer(f["integral"], self.disc.tip) - f["gram"])'),
    _m("out_of_plane", "spring", FLIP, OOP,
       "S += kappa * np.outer(b, b) +",
       "S += -kappa * np.outer(b, b) +"),
    _m("out_of_plane", "spring (axial force)", FLIP, OOP,
       "+ (P * (rule.w * axial)[:, None]).T @ P",
       "- (P * (rule.w * axial)[:, None]).T @ P"),
    _m("out_of_plane", "end_mass_inertia", FLIP, OOP,
       'M = M + G * np.outer(f["integral"], f["integral"])',
       'M = M - G * np.outer(f["integral"], f["integral"])'),
    _m("out_of_plane", "coriolis", FLIP, OOP,
       'return 2.0 * p.v * math.sqrt(p.beta) * self.fixed()["coriolis"]',
       'return -2.0 * p.v * math.sqrt(p.beta) * self.fixed()["coriolis"]'),
    _m("out_of_plane", "coriolis", "drop factor 2", OOP,
       'return 2.0 * p.v * math.sqrt(p.beta) * self.fixed()["coriolis"]',
       'return p.v * math.sqrt(p.beta) * self.fixed()["coriolis"]'),
    _m("out_of_plane", "external_damping", FLIP, OOP,
       'return self.params.external_damping * self.fixed()["mass"]',
       'return -self.params.external_damping * self.fixed()["mass"]'),
    _m("out_of_plane", "kelvin_voigt", FLIP, OOP,
       "C = C + p.mu * material",
       "C = C - p.mu * material"),
    _m("out_of_plane", "kelvin_voigt (spin)", FLIP, OOP,
       'return f["dPhi"] + d * self.quad.cumulative(d * f["Phi"])',
       'return f["dPhi"] - d * self.quad.cumulative(d * f["Phi"])'),
    _m("out_of_plane", "hysteretic", FLIP, OOP,
       "return ops.material_bending(ops.state(q))",
       "return -ops.material_bending(ops.state(q))"),
    # ------------------------------------------- out of the plane, moving state --
    _m("out_of_plane", "coriolis (moving state)", FLIP, OM,
       "flow = (2.0 * p.v * math.sqrt(p.beta)) * t_dot",
       "flow = -(2.0 * p.v * math.sqrt(p.beta)) * t_dot"),
    Mutation("out_of_plane", "flow_acceleration (moving state's force)", FLIP, f"fempipe/{OM}",
             "flow = flow + (v_dot * math.sqrt(p.beta)) * t",
             "flow = flow - (v_dot * math.sqrt(p.beta)) * t", (BENT,)),
    Mutation("out_of_plane", "flow_acceleration (stiffness)", FLIP, f"fempipe/{OM}",
             "return (v_dot * math.sqrt(self.params.beta)) * self.static.fixed()",
             "return -(v_dot * math.sqrt(self.params.beta)) * self.static.fixed()", (BENT,)),
    _m("out_of_plane", "follower (moving state)", FLIP, OM,
       "G += (p.v * p.v) * np.array(",
       "G -= (p.v * p.v) * np.array("),
    _m("out_of_plane", "gravity (moving state)", FLIP, OM,
       "G -= p.gamma * (1.0 - self.x + p.end_mass)[:, None] * g",
       "G += p.gamma * (1.0 - self.x + p.end_mass)[:, None] * g"),
    _m("out_of_plane", "end_mass_inertia (moving state)", FLIP, OM,
       "G += p.end_mass * quad.integrate(t_ddot)",
       "G -= p.end_mass * quad.integrate(t_ddot)"),
    _m("out_of_plane", "external_damping (moving state)", FLIP, OM,
       "inner = t_ddot + p.external_damping * t_dot",
       "inner = t_ddot - p.external_damping * t_dot"),
    _m("out_of_plane", "centripetal (moving state)", FLIP, OM,
       "t_ddot = b.accel[:, None] * n - (b.rate**2)[:, None] * t",
       "t_ddot = b.accel[:, None] * n + (b.rate**2)[:, None] * t"),
    _m("out_of_plane", "axial force (moving state)", FLIP, OM,
       "return -self.static.weighted_gram(np.cos(theta)",
       "return self.static.weighted_gram(np.cos(theta)"),
    _m("out_of_plane", "follower (jet, moving state)", FLIP, OM,
       "return (self.params.v**2) * np.outer(",
       "return -(self.params.v**2) * np.outer("),
    _m("out_of_plane", "kelvin_voigt stiffness: spin (moving state)", FLIP, OM,
       "* Phi - d * C(b.rate[:, None] * dPhi)",
       "* Phi + d * C(b.rate[:, None] * dPhi)"),
    _m("out_of_plane", "kelvin_voigt stiffness: bending rate (moving state)", FLIP, OM,
       "- self.static.weighted_gram(b.drate * dtheta)",
       "+ self.static.weighted_gram(b.drate * dtheta)"),
    _m("out_of_plane", "kelvin_voigt stiffness: tilt (moving state)", FLIP, OM,
       "- tilt.T @ (b.drate[:, None] * dPhi)",
       "+ tilt.T @ (b.drate[:, None] * dPhi)"),
    _m("out_of_plane", "external_damping (moving state, C)", FLIP, OM,
       "C = C + s.external_damping()",
       "C = C - s.external_damping()"),
    # ---------------------------------------------------------------------- 3-D --
    _m("3d", "inertia", FLIP, SP,
       'return self._integral(self._integral(fl.t_ddot, "C"), "CR")',
       'return -self._integral(self._integral(fl.t_ddot, "C"), "CR")'),
    _m("3d", "coriolis", FLIP, SP,
       "return (2.0 * p.v * np.sqrt(p.beta)) * self._integral(fl.t_dot",
       "return (-2.0 * p.v * np.sqrt(p.beta)) * self._integral(fl.t_dot"),
    _m("3d", "coriolis", "drop factor 2", SP,
       "return (2.0 * p.v * np.sqrt(p.beta)) * self._integral(fl.t_dot",
       "return (p.v * np.sqrt(p.beta)) * self._integral(fl.t_dot"),
    _m("3d", "coriolis", "flip the out-of-plane component", SP,
       'return (2.0 * p.v * np.sqrt(p.beta)) * self._integral(fl.t_dot, "CR")',
       'return (2.0 * p.v * np.sqrt(p.beta)) * self._integral(fl.t_dot, "CR")'
       " * np.array([1.0, 1.0, -1.0])[None, :, None]"),
    _m("3d", "flow_acceleration", FLIP, SP,
       "return (v_dot * np.sqrt(self.params.beta)) * self._integral(",
       "return (-v_dot * np.sqrt(self.params.beta)) * self._integral("),
    _m("3d", "flow_acceleration", "drop factor sqrt(beta)", SP,
       "return (v_dot * np.sqrt(self.params.beta)) * self._integral(",
       "return v_dot * self._integral("),
    _m("3d", "follower", FLIP, SP,
       "return (v * v) * fl.t_tip",
       "return (-v * v) * fl.t_tip"),
    _m("3d", "follower", "flip the out-of-plane component", SP,
       "return (v * v) * fl.t_tip",
       "return (v * v) * fl.t_tip * np.array([1.0, 1.0, -1.0])[None, :, None]"),
    _m("3d", "gravity", FLIP, SP,
       "return -p.gamma * lever[:, None, None]",
       "return p.gamma * lever[:, None, None]"),
    _m("3d", "end_mass_inertia", FLIP, SP,
       'return G * self._integral(fl.t_ddot, "int")',
       'return -G * self._integral(fl.t_ddot, "int")'),
    _m("3d", "end_mass_inertia", "flip the out-of-plane component", SP,
       'return G * self._integral(fl.t_ddot, "int")',
       'return G * self._integral(fl.t_ddot, "int") * np.array([1.0, 1.0, -1.0])[None, :, None]'),
    _m("3d", "external_damping", FLIP, SP,
       'return sigma * self._integral(rdot, "CR")',
       'return -sigma * self._integral(rdot, "CR")'),
    _m("3d", "external_damping", "flip the out-of-plane component", SP,
       'return sigma * self._integral(rdot, "CR")',
       'return sigma * self._integral(rdot, "CR") * np.array([1.0, 1.0, -1.0])[None, :, None]'),
    _m("3d", "bending", "flip the curvature-variation part", SP,
       "A = stack([dot(tp, fl.dt_prime[c]) for c in range(3)], axis=1)",
       "A = -stack([dot(tp, fl.dt_prime[c]) for c in range(3)], axis=1)"),
    _m("3d", "kelvin_voigt", FLIP, SP,
       "return mu * A, mu * B",
       "return -mu * A, -mu * B"),
    _m("3d", "kelvin_voigt", "flip the A part", SP,
       "return mu * A, mu * B",
       "return -mu * A, mu * B"),
    _m("3d", "kelvin_voigt", "flip the B part", SP,
       "return mu * A, mu * B",
       "return mu * A, -mu * B"),
    _m("3d", "kelvin_voigt", "flip the tail C^R(k . t')", SP,
       "+ dot(fl.J[c], tpxt) for c in range(3)",
       "- dot(fl.J[c], tpxt) for c in range(3)"),
    _m("3d", "kelvin_voigt", "flip the spin Omega t'", SP,
       "return cross(fl.t, fl.t_dot_prime) + fl.t_prime * Omega[:, None]",
       "return cross(fl.t, fl.t_dot_prime) - fl.t_prime * Omega[:, None]"),
    _m("3d", "kelvin_voigt", "drop the spin Omega t'", SP,
       "return cross(fl.t, fl.t_dot_prime) + fl.t_prime * Omega[:, None]",
       "return cross(fl.t, fl.t_dot_prime) + 0.0 * fl.t_prime * Omega[:, None]"),
    _m("3d", "gauge", "flip fiber_dot . u_dot", SP,
       "+ dot(fl.fiber_dot, fl.u_dot)",
       "- dot(fl.fiber_dot, fl.u_dot)"),
    _m("3d", "gauge", "flip its damping", SP,
       "+ self.gauge_damping * rate",
       "- self.gauge_damping * rate"),
    _m("3d", "gauge", "flip its stiffness", SP,
       "+ self.gauge_stiffness * (f[:, 1]",
       "- self.gauge_stiffness * (f[:, 1]"),
    _m("3d", "gauge", FLIP, SP,
       "return f * (self.gauge_weight * r)[:, None]",
       "return f * (-self.gauge_weight * r)[:, None]"),
    _m("3d", "coriolis (dR/dv)", FLIP, SP,
       'G = 2.0 * np.sqrt(p.beta) * self._integral(fl.t_dot, "CR") + (2.0 * p.v) * fl.t_tip',
       'G = -2.0 * np.sqrt(p.beta) * self._integral(fl.t_dot, "CR") + (2.0 * p.v) * fl.t_tip'),
    _m("3d", "follower (dR/dv)", FLIP, SP,
       'G = 2.0 * np.sqrt(p.beta) * self._integral(fl.t_dot, "CR") + (2.0 * p.v) * fl.t_tip',
       'G = 2.0 * np.sqrt(p.beta) * self._integral(fl.t_dot, "CR") - (2.0 * p.v) * fl.t_tip'),
)  # fmt: skip


@dataclass(frozen=True)
class Outcome:
    """The JSON entry of one mutation."""

    model: str
    term: str
    change: str
    path: str
    killed: bool
    killed_by: str | None
    seconds: float


def apply(root: Path, m: Mutation) -> str:
    """Write the mutated file into the copy ``root``; return the original text."""
    path = (root / m.path).resolve()
    text = path.read_text()
    count = text.count(m.old)
    if count != 1:
        raise SystemExit(
            f"mutation_check: the snippet of '{m.term}' ({m.change}) occurs {count} times in "
            f"{m.path} (must be once): {m.old!r}"
        )
    path.write_text(text.replace(m.old, m.new))
    return text


_FAILED = re.compile(r"^(?:FAILED|ERROR) (\S+)", re.MULTILINE)


def run_one(root: Path, m: Mutation) -> Outcome:
    """Mutate the copy, run the model's tests there (stop at the first failure), restore."""
    original = apply(root, m)
    path = (root / m.path).resolve()
    env = dict(os.environ, PYTHONPATH=str(root), PYTHONDONTWRITEBYTECODE="1", MPLBACKEND="Agg")
    cmd = [sys.executable, "-m", "pytest", "-x", "-q", "-rfE", "--no-header",
           "-p", "no:cacheprovider", "-p", "no:randomly", *m.tests]  # fmt: skip
    t0 = time.perf_counter()
    try:
        proc = subprocess.run(
            cmd, cwd=root, env=env, capture_output=True, text=True, timeout=TIMEOUT
        )
        out = proc.stdout + proc.stderr
        found = _FAILED.findall(out)
        if "ERROR collecting" in out:  # the copy, not the mutation: the check cannot run
            raise SystemExit(f"mutation_check: pytest could not collect the tests:\n{out[-2000:]}")
        if proc.returncode == 0:
            killed, by = False, None
        elif found:
            killed, by = True, found[0]
        else:
            tail = out.strip().splitlines()[-3:]
            raise SystemExit(f"mutation_check: pytest exited {proc.returncode}: {tail}")
    except subprocess.TimeoutExpired:
        killed, by = True, f"timeout ({TIMEOUT:g} s)"
    finally:
        path.write_text(original)
    return Outcome(m.model, m.term, m.change, m.path, killed, by, time.perf_counter() - t0)


def copy_tree(dest: Path) -> Path:
    """The repository's package and tests (what the test runs need), without caches."""
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc", "_build")
    for name in ("fempipe", "tests", "docs", "examples", "validation"):
        if (ROOT / name).exists():
            shutil.copytree(ROOT / name, dest / name, ignore=ignore)
    for name in ("pyproject.toml", "README.md"):
        shutil.copy2(ROOT / name, dest / name)
    return dest


def run_all(mutations, workers: int, progress) -> list[Outcome]:
    """Every mutation, on ``workers`` copies of the repository at once."""
    jobs: queue.Queue = queue.Queue()
    for i, m in enumerate(mutations):
        jobs.put((i, m))
    results: list[Outcome | None] = [None] * len(mutations)
    errors: list[BaseException] = []

    def work(root: Path) -> None:
        while not errors:
            try:
                i, m = jobs.get_nowait()
            except queue.Empty:
                return
            try:
                results[i] = run_one(root, m)
            except BaseException as exc:  # reported by the main thread
                errors.append(exc)
                return
            progress(results[i])

    with tempfile.TemporaryDirectory(prefix="fempipe-mutation-") as tmp:
        roots = [copy_tree(Path(tmp) / f"copy{k}") for k in range(workers)]
        threads = [threading.Thread(target=work, args=(r,)) for r in roots]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
    if errors:
        raise errors[0]
    return [r for r in results if r is not None]


def table(outcomes: list[Outcome]) -> str:
    rows = [("model", "term", "change", "killed", "killed by", "s")]
    for o in outcomes:
        by = (o.killed_by or "-").replace("tests/", "")
        rows.append((o.model, o.term, o.change, "yes" if o.killed else "SURVIVED", by,
                     f"{o.seconds:.0f}"))  # fmt: skip
    widths = [max(len(r[k]) for r in rows) for k in range(len(rows[0]))]
    return "\n".join("  ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)) for r in rows)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true", help="print JSON on stdout")
    ap.add_argument("--only", metavar="TEXT", help="only mutations whose model or term has TEXT")
    ap.add_argument("--workers", type=int, default=2, help="copies run at once (default 2)")
    ap.add_argument("--list", action="store_true", help="list the mutations and exit")
    args = ap.parse_args(argv)
    if args.workers < 1:
        ap.error(f"--workers must be at least 1, got {args.workers}")
    chosen = [m for m in MUTATIONS if not args.only or args.only in m.model or args.only in m.term]
    if args.list:
        for m in chosen:
            print(f"{m.model:13s} {m.term:45s} {m.change}")
        return 0
    if not chosen:
        ap.error(f"--only {args.only!r} matches no mutation")
    for m in chosen:  # every snippet must be there before anything runs
        n = (ROOT / m.path).resolve().read_text().count(m.old)
        if n != 1:
            ap.error(f"the snippet of {m.model} '{m.term}' ({m.change}) occurs {n} times")

    def progress(o: Outcome) -> None:
        state = f"killed by {o.killed_by}" if o.killed else "SURVIVED"
        print(f"mutation_check: {o.model} {o.term} ({o.change}): {state}, {o.seconds:.0f} s",
              file=sys.stderr, flush=True)  # fmt: skip

    t0 = time.perf_counter()
    outcomes = run_all(chosen, args.workers, progress)
    wall = time.perf_counter() - t0
    survivors = [o for o in outcomes if not o.killed]
    if args.json:
        print(json.dumps({"mutations": [asdict(o) for o in outcomes],
                          "survivors": len(survivors), "wall_seconds": wall}, indent=1))  # fmt: skip
    else:
        print(table(outcomes))
        print(f"{len(outcomes) - len(survivors)} killed, {len(survivors)} survived "
              f"in {wall:.0f} s on {args.workers} copies")  # fmt: skip
    return 1 if survivors else 0


if __name__ == "__main__":
    sys.exit(main())
