"""The physics engines below the world: ``ode`` (SimSpark's own step on the Open Dynamics
Engine, the default) and ``mujoco`` (the fast approximation). Each provides a world class with
the same interface (:func:`robocup_gym.sim.make_world` picks one); what is above the physics
step (game state, hearing, vision, perception) is :mod:`robocup_gym.sim.senses`, shared."""
