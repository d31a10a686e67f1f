"""Learned components: the LSTM zero-velocity classifier.

Training needs PyTorch (``pip install 'imunav[learn]'``, imported lazily);
inference (:class:`LstmDetector`) is numpy only.
"""

from imunav.learn.lstm import (
    DEFAULT_MODEL_PATH,
    SHOE_GUARD_GRID,
    LstmConfig,
    LstmDetector,
    TrainingReport,
    augment,
    best_labels,
    gravity_in_body,
    guard_stances,
    lstm_forward,
    random_rotations,
    select_shoe_threshold,
    time_warp,
    train_lstm,
)

__all__ = [
    "DEFAULT_MODEL_PATH",
    "SHOE_GUARD_GRID",
    "LstmConfig",
    "LstmDetector",
    "TrainingReport",
    "augment",
    "best_labels",
    "gravity_in_body",
    "guard_stances",
    "lstm_forward",
    "random_rotations",
    "select_shoe_threshold",
    "time_warp",
    "train_lstm",
]
