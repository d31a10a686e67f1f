"""The naming table of configuration fields, as data, and the check that applies it.

A name has one meaning and one unit across the package: a noise density, a per-sample standard deviation, a
random walk, a correlation time, an initial σ and a threshold each have one naming pattern.  :data:`NAMING_TABLE`
is the table of ``docs/design.md`` (§3.2.1); :func:`check_field_name` says what is wrong with a field name and
:func:`check_config_class` with every field of a configuration dataclass (``tests/test_vocabulary.py`` runs it over
every public ``*Config`` class of the package).

The patterns are read on the ``_``-separated words of a name: ``<x>`` stands for one or more words naming the
quantity (``gyro``, ``accel_bias``, ``mag_heading``), written in full (``accel``, not ``acc``).  A non-SI unit, when
a field has one, is the last word (``alpha_noise_std_deg``); a duration in seconds that is not one of the patterns
below ends in ``_s`` (``hold_s``, ``zaru_min_s``).
"""

from __future__ import annotations

import dataclasses

__all__ = ["NamingRule", "NAMING_TABLE", "FORBIDDEN_WORDS", "UNIT_SUFFIXES", "RENAMED_FIELDS", "check_field_name",
           "check_config_class", "renamed_hint"]


@dataclasses.dataclass(frozen=True)
class NamingRule:
    """One row of the naming table.

    Attributes
    ----------
    quantity : str
        What the field holds.
    pattern : str
        Its name, ``<x>`` standing for the quantity's words.
    unit : str
        Its unit.
    examples : tuple of str
        Fields of the package that follow it.
    """

    quantity: str
    pattern: str
    unit: str
    examples: tuple[str, ...]


#: The naming table (docs/design.md §3.2.1).
NAMING_TABLE: tuple[NamingRule, ...] = (
    NamingRule("white-noise density (the sensor's angle / velocity random walk)", "<x>_noise_density",
               "unit of x per √Hz (rad/s/√Hz = rad/√s; m/s²/√Hz = m/s/√s)",
               ("GinsConfig.gyro_noise_density", "MekfConfig.gyro_noise_density")),
    NamingRule("standard deviation of white noise per sample, of a measurement or of a sensor sampled at its rate",
               "<x>_noise_std", "unit of x",
               ("ZuptConfig.accel_noise_std", "GinsConfig.odo_noise_std", "FlightConfig.ps_noise_std")),
    NamingRule("bias random walk: density of the white noise driving a bias", "<x>_bias_random_walk",
               "unit of the bias per √s (rad/s/√s, m/s²/√s)",
               ("MekfConfig.gyro_bias_random_walk", "ZuptConfig.accel_bias_random_walk")),
    NamingRule("correlation time of a first-order Gauss–Markov process", "<x>_corr_time (or corr_time)", "s",
               ("GinsConfig.corr_time", "LongHorizonConfig.wind_corr_time")),
    NamingRule("steady (stationary) σ of a Gauss–Markov process, or the σ of a random constant (T = ∞)", "<x>_std",
               "unit of x", ("GinsConfig.gyro_bias_std", "LongHorizonConfig.turbulence_std", "GinsConfig.mounting_std")),
    NamingRule("initial σ of a filter state", "init_<x>_std", "unit of x",
               ("GinsConfig.init_att_std", "ZuptConfig.init_pos_std", "MekfConfig.init_gyro_bias_std")),
    NamingRule("variance, where the source gives variances", "<x>_var (initial: init_<x>_var)", "unit of x, squared",
               ("LongHorizonConfig.init_wind_var", "BodyWindFilterConfig.wind_step_var")),
    NamingRule("threshold a test compares a quantity with", "<x>_threshold", "unit of x",
               ("MekfConfig.rest_gyro_threshold", "GravityKfConfig.accel_norm_threshold", "LstmConfig.threshold")),
    NamingRule("time constant of a low-pass or a correction (not a Gauss–Markov process)", "<x>_time_constant", "s",
               ("MekfConfig.accel_lpf_time_constant", "MekfConfig.tilt_time_constant")),
    NamingRule("a record of the noise fields above (a sub-configuration)", "<x>_noise_model", "(its fields')",
               ("KfGinsConfig.imu_noise_model",)),
    NamingRule("gravity magnitude", "g (default imunav.units.DEFAULT_GRAVITY)", "m/s²",
               ("MekfConfig.g", "ZuptConfig.g")),
)

#: Words no field name may contain, and what to write instead.
FORBIDDEN_WORDS: dict[str, str] = {
    "sigma": "<x>_noise_std (per sample), <x>_noise_density (density) or <x>_std (Gauss–Markov / constant)",
    "p0": "init_<x>_std (or init_<x>_var)",
    "arw": "gyro_noise_density",
    "vrw": "accel_noise_density",
    "rrw": "gyro_bias_random_walk",
    "rw": "<x>_bias_random_walk",
    "tau": "<x>_corr_time (Gauss–Markov) or <x>_time_constant (filter) or <x>_threshold",
    "tol": "<x>_threshold",
    "acc": "accel",
    "initial": "init_<x>_std",
    "sd": "<x>_std",
    "stdev": "<x>_std",
    "variance": "<x>_var",
}

#: Unit words a field name may end with after a pattern (non-SI units, or seconds of a plain duration).
UNIT_SUFFIXES: tuple[str, ...] = ("deg", "dps", "hz", "s", "c", "m", "ppm", "mg", "ug")


#: The configuration fields issue 25 renamed, by class: old name -> new name.  Only for the messages that refuse an
#: old name in a TOML file or a ``--param`` option (:func:`renamed_hint`); the old names are not accepted.
RENAMED_FIELDS: dict[str, dict[str, str]] = {
    "GinsConfig": {"arw": "gyro_noise_density", "vrw": "accel_noise_density", "odo_noise": "odo_noise_std",
                   "nhc_noise": "nhc_noise_std", "zupt_noise": "zupt_noise_std", "zaru_noise": "zaru_noise_std",
                   "baro_noise": "baro_noise_std", "mag_heading_noise": "mag_heading_noise_std",
                   "level_std": "level_noise_std"},
    "MekfConfig": {"sigma_gyro": "gyro_noise_density", "sigma_bias": "gyro_bias_random_walk",
                   "sigma_acc": "accel_direction_noise_std", "k_acc": "k_accel", "acc_reject": "accel_reject_threshold",
                   "sigma_mag": "heading_noise_std", "mag_norm_tol": "mag_norm_threshold",
                   "mag_dip_tol": "mag_dip_threshold", "rest_gyro": "rest_gyro_threshold",
                   "rest_acc": "rest_accel_threshold", "sigma_rest": "zaru_noise_std",
                   "ref_tau": "mag_ref_time_constant", "acc_lpf_tau": "accel_lpf_time_constant",
                   "rest_lpf_tau": "rest_lpf_time_constant", "mag_lpf_tau": "mag_lpf_time_constant",
                   "bias_clip": "lpf_gyro_threshold", "tau_acc": "tilt_time_constant",
                   "tau_mag": "heading_time_constant", "p0_att": "init_att_std", "p0_bias": "init_gyro_bias_std"},
    "UkfConfig": {"sigma_gyro": "gyro_noise_density", "sigma_bias": "gyro_bias_random_walk",
                  "sigma_acc": "accel_direction_noise_std", "sigma_mag": "mag_direction_noise_std",
                  "acc_reject": "accel_reject_threshold", "p0_att": "init_att_std", "p0_bias": "init_gyro_bias_std"},
    "GravityKfConfig": {"sigma_g": "gyro_noise_std", "sigma_a": "accel_noise_std", "tau": "accel_norm_threshold",
                        "sigma_b": "gyro_bias_random_walk", "r_b": "bias_pseudo_noise_std", "p0": "init_std"},
    "ZuptConfig": {"sigma_acc": "accel_noise_std", "sigma_gyro": "gyro_noise_std", "sigma_v": "zupt_noise_std",
                   "sigma_acc_bias_rw": "accel_bias_random_walk", "sigma_gyro_bias_rw": "gyro_bias_random_walk",
                   "p0_pos": "init_pos_std", "p0_vel": "init_vel_std", "p0_att": "init_att_std",
                   "p0_acc_bias": "init_accel_bias_std", "p0_gyro_bias": "init_gyro_bias_std",
                   "initial_yaw": "init_yaw", "sigma_zaru": "zaru_noise_std", "sigma_heading": "heading_noise_std",
                   "sigma_floor": "floor_noise_std"},
    "LstmConfig": {"noise_acc": "accel_noise_std", "noise_gyro": "gyro_noise_std"},
    "BodyWindFilterConfig": {"tau": "wind_corr_time", "q": "wind_step_var", "p0": "init_var",
                             "sigma_ads": "ads_noise_std", "sigma_doppler": "doppler_noise_std"},
    "LongHorizonConfig": {"wind_sigma": "wind_std", "wind_tau": "wind_corr_time", "turbulence_sigma": "turbulence_std",
                          "turbulence_tau": "turbulence_corr_time", "sigma_ads": "ads_noise_std",
                          "sigma_doppler": "doppler_noise_std", "p0_wind": "init_wind_var",
                          "p0_position": "init_position_var"},
    "FlightConfig": {"sigma_ps": "ps_noise_std", "sigma_qc": "qc_noise_std", "sigma_tat": "tat_noise_std",
                     "sigma_alpha_deg": "alpha_noise_std_deg", "sigma_beta_deg": "beta_noise_std_deg",
                     "sigma_attitude_deg": "attitude_noise_std_deg"},
    "KfGinsConfig": {"noise": "imu_noise_model"},
}


def renamed_hint(config: str, names: object) -> str:
    """The part of an error message that says which of ``names`` were renamed, and to what ("" if none).

    Parameters
    ----------
    config : str
        The configuration class's name (a key of :data:`RENAMED_FIELDS`).
    names : iterable of str
        The unknown names a user gave.

    Returns
    -------
    str
        ``" (renamed: arw -> gyro_noise_density, ...)"``, or ``""``.
    """
    table = RENAMED_FIELDS.get(config, {})
    hits = [f"{n} -> {table[n]}" for n in names if n in table]  # type: ignore[attr-defined]
    return f" (renamed: {', '.join(hits)})" if hits else ""


def _tail_ok(words: list[str], i: int) -> bool:
    """The pattern word at ``i`` is the last word, or followed only by one unit word."""
    rest = words[i + 1:]
    return not rest or (len(rest) == 1 and rest[0] in UNIT_SUFFIXES)


def check_field_name(name: str) -> list[str]:
    """What is wrong with a configuration field's name under the naming table (empty: nothing).

    Parameters
    ----------
    name : str
        The field name.

    Returns
    -------
    list of str
        One sentence per broken rule, saying what to write instead.
    """
    words = name.lower().split("_")
    problems = [f"{name!r}: the word {w!r} is not used in a field name; write {FORBIDDEN_WORDS[w]}"
                for w in words if w in FORBIDDEN_WORDS]
    for i, w in enumerate(words):
        nxt = words[i + 1] if i + 1 < len(words) else None
        prev = words[i - 1] if i > 0 else None
        if w == "noise" and nxt not in ("std", "density", "model"):
            problems.append(f"{name!r}: noise is <x>_noise_std (σ per sample), <x>_noise_density (per √Hz) or "
                            "<x>_noise_model (a record of such fields)")
        elif w in ("std", "var", "threshold") and not _tail_ok(words, i):
            problems.append(f"{name!r}: '{w}' ends the name (<x>_{w}, then at most a unit word)")
        elif w == "density" and (prev != "noise" or not _tail_ok(words, i)):
            problems.append(f"{name!r}: a density is <x>_noise_density")
        elif w == "random" and (nxt != "walk" or prev != "bias" or not _tail_ok(words, i + 1)):
            problems.append(f"{name!r}: a random walk is <x>_bias_random_walk")
        elif w == "corr" and (nxt != "time" or not _tail_ok(words, i + 1)):
            problems.append(f"{name!r}: a correlation time is <x>_corr_time")
        elif w == "constant" and (prev != "time" or not _tail_ok(words, i)):
            problems.append(f"{name!r}: a time constant is <x>_time_constant")
        elif w == "init" and i != 0:
            problems.append(f"{name!r}: an initial value starts with init_ (init_<x>_std)")
    return problems


def check_config_class(cls: type) -> list[str]:
    """What is wrong with the fields of a configuration dataclass (empty: nothing).

    Every field name must pass :func:`check_field_name`, and every field must be typed without ``Any``.

    Parameters
    ----------
    cls : type
        A dataclass.

    Returns
    -------
    list of str
        One sentence per problem, naming the class and the field.

    Raises
    ------
    TypeError
        If ``cls`` is not a dataclass.
    """
    if not dataclasses.is_dataclass(cls):
        raise TypeError(f"{cls!r} is not a dataclass")
    out = []
    for f in dataclasses.fields(cls):
        out += [f"{cls.__name__}.{p}" for p in check_field_name(f.name)]
        ann = f.type if isinstance(f.type, str) else getattr(f.type, "__name__", repr(f.type))
        if "Any" in ann.replace("[", " ").replace("]", " ").replace(",", " ").replace("|", " ").split():
            out.append(f"{cls.__name__}.{f.name!r}: typed {ann!r}; give it a type without Any")
    return out
