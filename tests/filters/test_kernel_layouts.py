"""Named kernel layouts: the index constants of the kernels follow the configuration dataclasses.

A kernel reads its parameters through constants (``p[P_GYRO_NOISE_DENSITY]``, ``st[S_REST_TIMER]``, ``dx[I_VEL]``); these
tests fail when a field is added, removed or reordered on one side only.
"""

from dataclasses import fields

import numpy as np

from imunav.attitude import _kernels as ak
from imunav.attitude.mekf import MekfConfig
from imunav.attitude.ukf import UkfConfig
from imunav.ins.zupt import ZuptConfig
from imunav.ins.zupt import kernels as ik


def test_mekf_parameter_constants_index_the_packed_config():
    names = {f.name for f in fields(MekfConfig)}
    assert set(ak.MEKF_PARAMS) <= names
    assert names - set(ak.MEKF_PARAMS) == {"init_att_std", "init_gyro_bias_std"}  # initial covariance, not a kernel parameter
    # distinct values per field: each constant must pick its own field out of vector()
    kw = {n: 0.5 + i for i, n in enumerate(ak.MEKF_PARAMS) if n not in ("use_mag", "mag_bias")}
    vec = MekfConfig(**kw, use_mag=True, mag_bias=False).vector()
    assert vec.shape == (ak.N_PARAMS,)
    for name, value in kw.items():
        assert vec[getattr(ak, "P_" + name.upper())] == value, name
    assert vec[ak.P_USE_MAG] == 1.0 and vec[ak.P_MAG_BIAS] == 0.0


def test_ukf_vector_uses_the_same_layout():
    v = UkfConfig(gyro_noise_density=1.0, gyro_bias_random_walk=2.0, accel_direction_noise_std=3.0, accel_reject_threshold=4.0, mag_direction_noise_std=5.0, g=6.0).vector(True)
    picked = v[[ak.P_GYRO_NOISE_DENSITY, ak.P_GYRO_BIAS_RANDOM_WALK, ak.P_ACCEL_DIRECTION_NOISE_STD, ak.P_ACCEL_REJECT_THRESHOLD, ak.P_HEADING_NOISE_STD, ak.P_G]]
    np.testing.assert_array_equal(picked, [1, 2, 3, 4, 5, 6])
    assert v[ak.P_USE_MAG] == 1.0


def test_mekf_state_layout_is_contiguous():
    starts = [getattr(ak, "S_" + name.upper()) for name, _ in ak.MEKF_STATE]
    ends = [s + n for s, (_, n) in zip(starts, ak.MEKF_STATE)]
    assert starts[0] == 0 and starts[1:] == ends[:-1] and ends[-1] == ak.N_STATE


def test_zupt_error_state_and_parameter_record():
    assert (ik.I_POS, ik.I_VEL, ik.I_ATT, ik.I_BA, ik.I_BG) == (0, 3, 6, 9, 12)
    assert ik.NX_NAV == ik.I_BA and ik.NX_BIAS == ik.I_BG + 3
    cfg_names = {f.name for f in fields(ZuptConfig)}
    # every parameter of the kernel record is a config field (g: resolved when None), except two derived ones
    assert set(ik.ZuptKernelParams._fields) - cfg_names == {"nx", "coning"}  # from states and integration


def test_gravity_parameter_constants_index_the_packed_config():
    from imunav.attitude import _gravity_kernels as gk
    from imunav.attitude.gravity_kf import GravityKfConfig

    names = {f.name for f in fields(GravityKfConfig)}
    assert set(gk.GRAVITY_PARAMS) <= names and names - set(gk.GRAVITY_PARAMS) == {"init_std"}
    p = GravityKfConfig(gyro_noise_std=1.0, accel_noise_std=2.0, c_a=3.0, g=4.0, accel_norm_threshold=5.0, s_mode="C", s_fixed=7.0, hold_s=8.0,
                        normalize=True, exact=False, gyro_bias_random_walk=11.0, bias_pseudo_noise_std=12.0, bias_window=13)
    v = p.vector()
    for name, want in (("gyro_noise_std", 1), ("accel_noise_std", 2), ("c_a", 3), ("g", 4), ("accel_norm_threshold", 5), ("s_mode", 2),
                       ("s_fixed", 7), ("hold_s", 8), ("normalize", 1), ("exact", 0), ("gyro_bias_random_walk", 11), ("bias_pseudo_noise_std", 12),
                       ("bias_window", 13)):
        assert v[getattr(gk, "G_" + name.upper())] == want, name
    assert gk.SV_BIAS_COUNT == gk.N_SV - 1
