"""Training, evaluation, export and the paper's experiments (``robocup-gym`` CLI).

Needs the ``train`` extra: ``pip install -e '.[train]'``.
"""

from robocup_gym.train.config import TrainConfig

__all__ = ["TrainConfig"]
