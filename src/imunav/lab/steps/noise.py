"""Lab step: identify the stochastic errors of the virtual IMU's long static record.

Reads ``ctx.artifacts["recordings"]["static_long"]`` and the true
``ctx.artifacts["error_model"]`` written by ``simulate_tests``; computes the
overlapping Allan deviation of the six channels, fits white noise N plus a
first-order Gauss-Markov term (the thesis_sim bias instability) by GLS with
95 % intervals, the AR(1) Gauss-Markov model (Yule-Walker on block-decimated
data) and the PSD estimate of N, and compares them with the injected values.

Options (TOML table ``[noise]``)::

    record = "static_long"
    terms = ["N", "B", "K"]     # candidate IEEE-952 terms
    gauss_markov = 1            # Gauss-Markov terms added to the fit
    decimate_s = 1.0            # block length for the AR(1) fit (s)

Verdict: the true N inside the family-wise 95 % interval on all six axes
(each axis at 1 - 0.05/6, Bonferroni: a plain 95 % interval on six axes
would fail one in four honest runs) and the
Gauss-Markov sigma within 35 % (one hour holds ~360 correlation times of
10 s: its sigma is known to ~10-20 %).

Files: ``figures/noise_allan_gyro.png``, ``figures/noise_allan_accel.png``,
``data/noise_fit.json``.  Artifacts set: ``"noise_fit"`` {"gyro", "accel"}: NoiseFit.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from imunav._quantiles import norm_ppf
from imunav.errors import ConfigError
from imunav.files import atomic_path, write_json
from imunav.lab.steps._api import LabContext, StepResult, recordings_before
from imunav.noise import allan_deviation, compare_psd_allan, fit_noise, fit_psd, log_average, psd
from imunav.noise.ar import fit_gauss_markov
from imunav.noise.plot import plot_allan
from imunav.units import to_display

#: two-sided normal quantile for a family-wise 95 % level over six axes (Bonferroni)
_Z_FAMILY = float(norm_ppf(1 - 0.05 / 12))

TITLE = "Noise identification of the static record (Allan GLS fit, PSD, AR(1))"

_DEFAULTS: dict[str, Any] = {"record": "static_long", "terms": ["N", "B", "K"], "gauss_markov": 1,
                             "decimate_s": 1.0}


def requires(lab: Any, earlier: Sequence[str]) -> list[str]:
    """The earlier steps this step takes its inputs from, checked before the lab runs.

    Parameters
    ----------
    lab : imunav.lab.config.LabConfig
        The typed lab definition.
    earlier : sequence of str
        The steps that run before this one.

    Returns
    -------
    list of str
        ``simulate_tests`` (the record and the true error model).

    Raises
    ------
    ConfigError
        When no earlier ``simulate_tests`` step makes the record (``[noise] record``) and the true model.
    """
    record = dict(lab.options.get("noise", {})).get("record", _DEFAULTS["record"])
    if "simulate_tests" not in earlier or recordings_before(lab, earlier).get(record) != "simulate_tests":
        raise ConfigError(f"[noise] needs the '{record}' recording and the true error model from the "
                          f"simulate_tests step: run simulate_tests before noise, with '{record}' in its tests")
    return ["simulate_tests"]


def run(ctx: LabContext) -> StepResult:
    """Run the step: see the module docstring for what it computes, its options, artifacts and files.

    Parameters
    ----------
    ctx : LabContext
        The lab's context: the step's option table ``ctx.options`` (``[noise]``), the artifacts it reads and
        sets, the report folder.

    Returns
    -------
    StepResult
        Fitted noise terms with their 95 % intervals against the injected truth.

    Raises
    ------
    ConfigError
        If ``[noise]`` has an unknown option, or the record or the true error model is missing.
    """
    opts = ctx.step_options(_DEFAULTS)
    recs = ctx.artifacts.get("recordings", {})
    model = ctx.artifacts.get("error_model")
    if opts["record"] not in recs or model is None:
        raise ConfigError(f"[noise] needs the '{opts['record']}' recording and the true error model from the "
                          "simulate_tests step (run it first, with that test enabled)")
    data = recs[opts["record"]]
    fs = float(round(data.fs, 6))
    rows: list[dict] = []
    figures = []
    fits = {}
    ok_n = []
    ok_gm = []
    with ctx.task("noise identification", total=2) as advance:
        for sensor, arr, triad, unit, du_n, du_b in (
            ("gyro", data.gyro, model.gyro, "rad/s", "deg/sqrt(h)", "deg/h"),
            ("accel", data.accel, model.accel, "m/s^2", "m/s/sqrt(h)", "ug"),
        ):
            names = tuple(f"{sensor[0]}{a}" for a in "xyz")
            r = allan_deviation(arr, fs, "octave", units=unit, channels=names)
            f = fit_noise(r, terms=tuple(opts["terms"]), gauss_markov=int(opts["gauss_markov"]), quantity=sensor)
            fits[sensor] = f
            pa = log_average(psd(arr, fs, "welch", nperseg=min(arr.shape[0], 2**14)), 10)
            pf = fit_psd(pa, f_range=[(pa.f[0], min(0.4 * fs, 0.5 / t)) for t in f.tau_min])
            cmp = compare_psd_allan(pf, f)["N"]
            bi = triad.bias_instability
            gm_true = (bi.sigma, bi.tau) if bi is not None and hasattr(bi, "tau") else (np.zeros(3), np.zeros(3))
            q = max(1, int(round(opts["decimate_s"] * fs)))
            iN = f.names.index("N")
            for c in range(3):
                n_true = float(triad.noise_density[c])
                # Six axes are checked together: a family-wise 95 % verdict needs
                # each axis inside its 1 - 0.05/6 interval (Bonferroni), z = 2.64.
                inside = bool(abs(f.value[iN, c] - n_true) <= _Z_FAMILY * f.se[iN, c])
                ok_n.append(inside)
                row = {
                    "axis": names[c],
                    f"N true [{du_n}]": round(float(to_display(n_true, du_n)), 5),
                    f"N fit [{du_n}]": round(float(to_display(f.value[iN, c], du_n)), 5),
                    "N 95% CI": f"[{to_display(f.ci_lo[iN, c], du_n):.5g}, {to_display(f.ci_hi[iN, c], du_n):.5g}]",
                    "N PSD/Allan-1": f"{cmp[c]:+.1%}",
                }
                if "GM1_sigma" in f.names:
                    iS, iT = f.names.index("GM1_sigma"), f.names.index("GM1_T")
                    s_true, t_true = float(gm_true[0][c]), float(gm_true[1][c])
                    row[f"GM sigma true/fit [{du_b}]"] = (f"{to_display(s_true, du_b):.4g} / "
                                                         f"{to_display(f.value[iS, c], du_b):.4g}")
                    row["GM T true/fit [s]"] = f"{t_true:.3g} / {f.value[iT, c]:.3g}"
                    if s_true > 0:
                        ok_gm.append(abs(f.value[iS, c] / s_true - 1) < 0.35)
                try:
                    # AR(1) of the block means; the white part is averaged down by the decimation
                    g = fit_gauss_markov(arr[:, c] - arr[:, c].mean(), fs, decimate=q)
                    row["AR(1) T [s]"] = round(g.T, 3)
                    row["1/e T [s]"] = round(g.T_acf, 3)
                except Exception as e:  # noqa: BLE001 - reported, not fatal
                    row["AR(1) T [s]"] = f"n/a ({type(e).__name__})"
                rows.append(row)
            fig = plot_allan(r, f, title=f"{sensor}: {opts['record']}")
            p = ctx.path("figures", f"noise_allan_{sensor}.png")
            with atomic_path(p) as tmp:
                fig.savefig(tmp, dpi=100)
            figures.append(p)
            advance()
    ctx.artifacts["noise_fit"] = fits
    out = ctx.path("data", "noise_fit.json")
    write_json(out, {k: v.to_dict() for k, v in fits.items()}, indent=1)
    passed = bool(all(ok_n) and (all(ok_gm) if ok_gm else True))
    summary = {
        "record": opts["record"], "fs": fs, "duration_s": data.n / fs,
        "N_true_inside_familywise_95ci": f"{sum(ok_n)}/{len(ok_n)}",
        "GM_sigma_within_35pct": f"{sum(ok_gm)}/{len(ok_gm)}" if ok_gm else "n/a",
    }
    return StepResult(summary=summary, figures=figures, passed=passed,
                      tables=[("Noise terms: truth vs identified", rows)],
                      notes=["Allan: overlapping ADEV, GLS-NNLS fit with the model covariance of the estimates "
                             "(imunav.noise.fit_noise); PSD: Welch, log-averaged, same band as the Allan fit."])
