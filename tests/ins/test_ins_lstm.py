"""LSTM zero-velocity detector: numpy inference vs torch, persistence, training, shipped model."""

from __future__ import annotations

import numpy as np
import pytest

from imunav.errors import ConfigError, FileFormatError, InvalidInputError, ShapeError
from imunav.learn import LstmConfig, LstmDetector, augment, lstm_forward, random_rotations, train_lstm
from imunav.learn.lstm import DEFAULT_MODEL_PATH
from imunav.sim.gait import simulate_gait


def test_numpy_forward_matches_torch():
    torch = pytest.importorskip("torch")
    torch.manual_seed(0)
    net = torch.nn.LSTM(6, 7, 2, batch_first=True)
    fc = torch.nn.Linear(7, 2)
    x = torch.randn(3, 25, 6)
    with torch.no_grad():
        ref = torch.softmax(fc(net(x)[0]), -1)[..., 1].numpy()
    sd = net.state_dict()
    w = [(sd[f"weight_ih_l{l}"].double().numpy(), sd[f"weight_hh_l{l}"].double().numpy(),
          (sd[f"bias_ih_l{l}"] + sd[f"bias_hh_l{l}"]).double().numpy()) for l in range(2)]
    out = lstm_forward(w, fc.weight.detach().double().numpy(), fc.bias.detach().double().numpy(), x.double().numpy())
    np.testing.assert_allclose(out, ref, atol=1e-6)
    with pytest.raises(ShapeError, match="batch, time"):
        lstm_forward(w, fc.weight.detach().numpy(), fc.bias.detach().numpy(), np.zeros((5, 6)))


def test_augmentation_rotations_are_rotations():
    rng = np.random.default_rng(1)
    R = random_rotations(50, np.pi, rng)
    np.testing.assert_allclose(R @ np.transpose(R, (0, 2, 1)), np.broadcast_to(np.eye(3), R.shape), atol=1e-12)
    np.testing.assert_allclose(np.linalg.det(R), 1.0, atol=1e-12)
    x = np.zeros((4, 10, 6))
    x[..., 2] = -9.8
    cfg = LstmConfig(noise_acc=0.0, noise_gyro=0.0, scale=(1.0, 1.0))
    y = augment(x, cfg, rng)
    np.testing.assert_allclose(np.linalg.norm(y[..., :3], axis=-1), 9.8, atol=1e-12)  # rotation keeps |f|


def test_train_save_load_detect(tmp_path):
    pytest.importorskip("torch")
    sims = [simulate_gait("walk", 8, error_model=None, rng=s) for s in range(2)]
    cfg = LstmConfig(layers=1, hidden=8, windows_per_trial=64, epochs=1, batch_size=32, burn_in=20)
    model, rep = train_lstm([s.imu for s in sims], [s.stance for s in sims], cfg)
    assert rep.n_windows == 128 and np.all(np.isfinite(rep.losses))
    path = model.save(tmp_path / "m.npz")
    m2 = LstmDetector.load(path)
    p1 = model.probability(sims[0].imu)
    np.testing.assert_allclose(m2.probability(sims[0].imu), p1, atol=1e-5)  # float32 storage
    assert p1.shape == (sims[0].imu.n,) and np.all((p1 >= 0) & (p1 <= 1))
    det = m2.detect(sims[0].imu)
    assert det.zv.dtype == bool and det.detector == "lstm"
    with pytest.raises(ShapeError, match="labels of trial 0"):
        train_lstm([sims[0].imu], [sims[0].stance[:10]], cfg)
    with pytest.raises(InvalidInputError, match="probability"):
        m2.detect(sims[0].imu, threshold=1.5)


def test_config_and_file_errors(tmp_path):
    with pytest.raises(ConfigError, match="burn_in"):
        LstmConfig(burn_in=100)
    with pytest.raises(ConfigError, match="threshold"):
        LstmConfig(threshold=1.0)
    assert LstmConfig.thesis().layers == 6 and LstmConfig.thesis().hidden == 80
    with pytest.raises(FileFormatError, match="not found"):
        LstmDetector.load(tmp_path / "none.npz")
    bad = tmp_path / "bad.npz"
    np.savez(bad, x=np.zeros(3))
    with pytest.raises(FileFormatError, match="not an imunav LSTM"):
        LstmDetector.load(bad)


def test_shipped_model_detects_simulated_stance():
    if not DEFAULT_MODEL_PATH.is_file():
        pytest.skip("shipped model not built yet")
    model = LstmDetector.load()
    assert DEFAULT_MODEL_PATH.stat().st_size < 500_000
    sim = simulate_gait("walk", 10, rng=4, error_model="foot_mems")
    zv = model.detect(sim.imu).zv
    # stance and swing are told apart on an unseen (simulated) IMU
    assert np.mean(zv[sim.stance]) > 0.5 and np.mean(zv[~sim.stance]) < 0.1
