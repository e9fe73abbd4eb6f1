"""Compatibility alias: the RobocupGym paper's ``EnvSimpleKick``.

See :mod:`robocup_gym.envs.compat`.

``EnvSimpleKick()`` is :class:`~robocup_gym.envs.tasks.SimpleKick` with the paper's constructor
(``env_config, vectorise_index, wait_steps, agent_type, …``) and attributes
(``python_agent_conn.player``, ``env_config``, …). New code should use ``SimpleKick``.
"""

from robocup_gym.envs.compat import PaperEnvMixin
from robocup_gym.envs.tasks.simple_kick import SimpleKick

__all__ = ["EnvSimpleKick"]


class EnvSimpleKick(PaperEnvMixin, SimpleKick):
    """The paper's ``EnvSimpleKick``: reward = distance the ball moved, paid once at the end
    (after ``wait_steps``, default 200)."""
