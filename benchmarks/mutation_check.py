"""Mutation check: do the tests catch small deliberate bugs?

Each mutant is one exact string replacement in one source file.  The source
tree is copied to a temporary directory, the mutant applied there (the working
tree is never modified, so Ctrl-C leaves nothing behind), and the mutant's
test selection is run with ``-x -q`` and PYTHONPATH pointing at the mutated
copy.  A mutant is *killed* when the tests fail, *survived* when they pass.
A replacement that does not match exactly once is reported as ``no-match``
(the list is stale), which also fails the check.

Usage::

    python benchmarks/mutation_check.py            # all mutants
    python benchmarks/mutation_check.py -k wind    # names containing "wind"

Not part of CI (a few minutes on 2 cores).  Exit status 0 only when every
selected mutant is killed.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


@dataclass(frozen=True)
class Mutant:
    name: str
    area: str
    path: str  # relative to src/imunav
    old: str
    new: str
    tests: tuple[str, ...]


MUTANTS = [
    # ---- the six mutants of issue 13
    Mutant("li-griffiths cross terms lose factor 2", "calibration", "calib/magnetometer.py",
           "D = np.stack([x * x, y * y, z * z, 2 * y * z, 2 * x * z, 2 * x * y, 2 * x, 2 * y, 2 * z, np.ones_like(x)])",
           "D = np.stack([x * x, y * y, z * z, y * z, x * z, x * y, 2 * x, 2 * y, 2 * z, np.ones_like(x)])",
           ("tests/calib/test_uncertainty_calibration.py",)),
    Mutant("magnetometer A stderr x sqrt(2)", "calibration", "calib/magnetometer.py",
           '"A": np.sqrt(np.maximum(np.diag(covA), 0)).reshape(3, 3)',
           '"A": np.sqrt(2.0 * np.maximum(np.diag(covA), 0)).reshape(3, 3)',
           ("tests/calib/test_uncertainty_calibration.py",)),
    Mutant("MEKF covariance update halved", "attitude", "filters/_core.py",
           "P[i, j] -= PH[i] * PH[j] / s",
           "P[i, j] -= 0.5 * PH[i] * PH[j] / s",
           ("tests/attitude/test_nees.py::test_mekf_public_covariance_is_the_kalman_recursion", "tests/attitude/test_nees.py::test_mekf_public_covariance_calibrated_static")),
    Mutant("long-horizon position ignores the gust (A[0,2] = 0)", "air data", "airdata/filter.py",
           "A = np.array([[0.0, 1.0, 1.0], [0.0, -1.0 / c.wind_corr_time, 0.0]",
           "A = np.array([[0.0, 1.0, 0.0], [0.0, -1.0 / c.wind_corr_time, 0.0]",
           ("tests/airdata/test_filter_calibration.py",)),
    Mutant("long-horizon gust process noise / 4", "air data", "airdata/filter.py",
           "2.0 * c.turbulence_std**2 / c.turbulence_corr_time",
           "0.5 * c.turbulence_std**2 / c.turbulence_corr_time",
           ("tests/airdata/test_filter_calibration.py",)),
    Mutant("thesis wind decay 1 - T/tau -> 1 + T/tau", "air data", "airdata/filter.py",
           "F[3:, 3:] = (1.0 - c.dt / c.wind_corr_time) * I3",
           "F[3:, 3:] = (1.0 + c.dt / c.wind_corr_time) * I3",
           ("tests/airdata/test_filter_calibration.py",)),
    Mutant("Madgwick field-gradient term of s0 sign-flipped", "attitude", "attitude/_kernels.py",
           "s0 += -2.0 * bz * q2 * e1",
           "s0 -= -2.0 * bz * q2 * e1",
           ("tests/attitude/test_ahrs_peer.py",)),
    # ---- two more per area
    Mutant("GM Allan series coefficient", "noise", "allan_models.py",
           "(2.0**k - 4.0) / (2.0 * math.factorial(k))",
           "(2.0**k - 3.0) / (2.0 * math.factorial(k))",
           ("tests/test_allan_models.py",)),
    Mutant("flicker Allan level B instead of B^2", "noise", "allan_models.py",
           "return np.full_like(tau, BI_FACTOR**2)",
           "return np.full_like(tau, BI_FACTOR)",
           ("tests/test_allan_models.py", "tests/noise/test_fit.py")),
    Mutant("Ferraris gyro-matrix stderr drops the bias term", "calibration", "calib/ferraris.py",
           "var_sum = n_rot * sig_g**2 + n_rot**2 * se_bg**2 + (se_G**2) @ (S**2)",
           "var_sum = n_rot * sig_g**2 + (se_G**2) @ (S**2)",
           ("tests/calib/test_uncertainty_calibration.py",)),
    Mutant("rate-table gyro-matrix stderr x 1.5", "calibration", "calib/ratetable.py",
           'stderr["gyro_matrix"] = fit.stderr[:3].T',
           'stderr["gyro_matrix"] = 1.5 * fit.stderr[:3].T',
           ("tests/calib/test_uncertainty_calibration.py",)),
    Mutant("MEKF gyro process noise doubled", "attitude", "attitude/_kernels.py",
           "        P[i, i] += sg2\n",
           "        P[i, i] += 2.0 * sg2\n",
           ("tests/attitude/test_nees.py::test_mekf_public_covariance_is_the_kalman_recursion", "tests/attitude/test_nees.py::test_mekf_public_covariance_calibrated_static")),
    Mutant("MEKF state correction halved", "attitude", "filters/_core.py",
           "dx[i] += PH[i] * nu / s",
           "dx[i] += 0.5 * PH[i] * nu / s",
           ("tests/attitude/test_nees.py::test_mekf_public_covariance_calibrated_static", "tests/attitude/test_filters_sim.py")),
    Mutant("MEKF tilt time constant scaled by dt instead of 1/dt", "attitude", "attitude/_kernels.py",
           "sa2 = (p[P_TILT_TIME_CONSTANT] * p[P_GYRO_NOISE_DENSITY]) ** 2 / dt if",
           "sa2 = (p[P_TILT_TIME_CONSTANT] * p[P_GYRO_NOISE_DENSITY]) ** 2 * dt if",
           ("tests/attitude/test_mekf.py",)),
    Mutant("MEKF field used without the minimum undisturbed time", "attitude", "attitude/_kernels.py",
           "if not disturbed and st[S_UNDISTURBED] >= p[P_MAG_MIN_UNDISTURBED] and hh > 1e-9 * mn:",
           "if not disturbed and hh > 1e-9 * mn:",
           ("tests/attitude/test_mekf.py",)),
    Mutant("MEKF heading update without the tilt leak through the dip", "attitude", "attitude/_kernels.py",
           "    Hy[4] = tan_dip\n",
           "    Hy[4] = 0.0 * tan_dip\n",
           ("tests/attitude/test_nees.py::test_mekf_public_covariance_calibrated_rotating_with_magnetometer",)),
    Mutant("MEKF rest test ignores the bias clip", "attitude", "attitude/_kernels.py",
           "and da < p[P_REST_ACCEL_THRESHOLD] * p[P_REST_ACCEL_THRESHOLD] and not big:",
           "and da < p[P_REST_ACCEL_THRESHOLD] * p[P_REST_ACCEL_THRESHOLD]:",
           ("tests/attitude/test_mekf.py",)),
    Mutant("Smoother covariance correction halved", "attitude", "attitude/_kernels.py",
           "Ps = Pu[k] + C @ (Ps - Pp[k + 1]) @ C.T",
           "Ps = Pu[k] + 0.5 * C @ (Ps - Pp[k + 1]) @ C.T",
           ("tests/attitude/test_nees.py::test_smoother_public_covariance_calibrated_rotating_with_magnetometer",)),
    Mutant("UKF covariance update halved", "attitude", "filters/_core.py",
           "    Pn = P - K @ Pzz @ K.T",
           "    Pn = P - 0.5 * K @ Pzz @ K.T",
           ("tests/attitude/test_nees.py::test_ukf_public_covariance_calibrated_static",
            "tests/attitude/test_nees.py::test_ukf_public_covariance_calibrated_rotating_with_magnetometer",
            "tests/filters/test_kalman.py::test_ukf_and_ekf_equal_kf_on_linear_model")),
    Mutant("ZUPT Joseph update without K R K^T", "ZUPT", "filters/_core.py",
           "acc += -X[i, idx[l]] * K[j, l] + K[i, l] * r[l] * K[j, l]",
           "acc += -X[i, idx[l]] * K[j, l]",
           ("tests/ins/test_zupt.py", "tests/ins/test_zupt_aids.py")),
    Mutant("ZUPT innovation covariance without R", "ZUPT", "filters/_core.py",
           "        S[i, i] += r[i]\n    inv_small(S, Si)",
           "        S[i, i] += 0.0 * r[i]\n    inv_small(S, Si)",
           ("tests/ins/test_zupt.py", "tests/ins/test_zupt_aids.py")),
    Mutant("noise-fit standard errors x 1.5", "noise", "noise/fit.py",
           "se[k, c] = s_th / (2.0 * v)",
           "se[k, c] = 1.5 * s_th / (2.0 * v)",
           ("tests/noise/test_fit_calibration.py",)),
    Mutant("noise-fit GM sigma se conditional on T", "noise", "noise/fit.py",
           "covth[np.ix_(keep, keep)] = cj[:nk, :nk]",
           "covth[np.ix_(keep, keep)] = np.linalg.inv(Jw[:, :nk].T @ Jw[:, :nk])",
           ("tests/noise/test_fit_calibration.py",)),
    Mutant("ZUPT attitude Jacobian from C_{k-1} f_k (not the increment)", "ZUPT", "ins/zupt/kernels.py",
           "_zupt_transition(Phi, Qd, dcm_from_quat_1(q[k - 1]), dvn, h, prm)",
           "_zupt_transition(Phi, Qd, dcm_from_quat_1(q[k - 1]), dcm_from_quat_1(q[k - 1]) @ (acc[k] - ba[k - 1]) * h, "
           "h, prm)",
           ("tests/ins/test_zupt_calibration.py",)),
    Mutant("ZUPT accelerometer process noise / 4", "ZUPT", "ins/zupt/kernels.py",
           "qa = prm.accel_noise_std * prm.accel_noise_std * h * h",
           "qa = 0.25 * prm.accel_noise_std * prm.accel_noise_std * h * h",
           ("tests/ins/test_zupt_calibration.py",)),
    Mutant("sim GM drive 1 - phi instead of 1 - phi^2", "simulation", "sim/_kernels.py",
           "math.sqrt(-math.expm1(-2.0 * d / gm_tau[i, j]))",
           "math.sqrt(-math.expm1(-1.0 * d / gm_tau[i, j]))",
           ("tests/sim/test_error_model.py",)),
    Mutant("sim white noise N sqrt(dt) instead of N / sqrt(dt)", "simulation", "sim/_kernels.py",
           "white_s[i] = nd[i] / math.sqrt(d)",
           "white_s[i] = nd[i] * math.sqrt(d)",
           ("tests/sim/test_error_model.py",)),
]


def run_mutant(m: Mutant, python: str, timeout: float) -> tuple[str, float]:
    t0 = time.time()
    with tempfile.TemporaryDirectory(prefix="imunav-mutant-") as tmp:
        src = Path(tmp) / "src"
        shutil.copytree(ROOT / "src", src, ignore=shutil.ignore_patterns("__pycache__", "*.nbc", "*.nbi"))
        f = src / "imunav" / m.path
        text = f.read_text()
        if text.count(m.old) != 1:
            return "no-match", time.time() - t0
        f.write_text(text.replace(m.old, m.new))
        env = {**os.environ, "PYTHONPATH": str(src), "NUMBA_CACHE_DIR": str(Path(tmp) / "numba"),
               "PYTHONDONTWRITEBYTECODE": "1"}
        env.pop("IMUNAV_SIGMA_SCALE", None)
        cmd = [python, "-m", "pytest", "-x", "-q", "-p", "no:cacheprovider", *m.tests]
        try:
            r = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, text=True, timeout=timeout, check=False)
        except subprocess.TimeoutExpired:
            return "killed (timeout)", time.time() - t0
        if r.returncode == 0:
            return "SURVIVED", time.time() - t0
        if r.returncode == 1:
            return "killed", time.time() - t0
        return f"error (pytest rc {r.returncode})", time.time() - t0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-k", default="", help="run only mutants whose name contains this text")
    ap.add_argument("--timeout", type=float, default=600.0, help="seconds per mutant")
    a = ap.parse_args(argv)
    sel = [m for m in MUTANTS if a.k.lower() in m.name.lower()]
    rows = []
    for m in sel:
        status, sec = run_mutant(m, sys.executable, a.timeout)
        rows.append((m.area, m.name, status, sec))
        print(f"{m.area:12s} {m.name:55s} {status:10s} {sec:6.1f} s", flush=True)
    print()
    print("| area | mutant | result | time |")
    print("|---|---|---|---|")
    for area, name, status, sec in rows:
        print(f"| {area} | {name} | {status} | {sec:.0f} s |")
    ok = all(s.startswith("killed") for _, _, s, _ in rows)
    print(f"\n{sum(s.startswith('killed') for _, _, s, _ in rows)}/{len(rows)} killed")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
