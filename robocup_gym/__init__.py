"""RoboCup Gym: the RoboCup 3D Soccer Simulation Nao world on MuJoCo, with Gymnasium environments.

Importing the package registers the environments (``RobocupGym/SimpleKick-v0``,
``RobocupGym/VelocityKick-v0``) with Gymnasium.
"""

from robocup_gym import envs as envs  # registers the Gymnasium ids

__version__ = "0.2.0"
