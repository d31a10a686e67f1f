"""Learned components: the LSTM zero-velocity classifier.

Training needs PyTorch (``pip install 'imunav[learn]'``, imported lazily);
inference (:class:`LstmDetector`) is numpy only.
"""

from imunav.learn.lstm import (
    DEFAULT_MODEL_PATH,
    LstmConfig,
    LstmDetector,
    TrainingReport,
    augment,
    best_labels,
    lstm_forward,
    random_rotations,
    train_lstm,
)

__all__ = ["DEFAULT_MODEL_PATH", "LstmConfig", "LstmDetector", "TrainingReport", "augment", "best_labels",
           "lstm_forward", "random_rotations", "train_lstm"]
