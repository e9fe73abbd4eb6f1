"""``python -m robocup_gym.cli``: the ``robocup-gym`` command."""

from robocup_gym.cli import main

main()
