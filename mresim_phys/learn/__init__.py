"""The learning interface (outer layer, beside the command line): PettingZoo and Gymnasium
environments built from scenario files (the ``learn`` extra: ``pip install -e ".[learn]"``).

* ``config``: what an environment is made of (scenarios, team sizes, the failure
  curriculum, the policy robots' observations and actions, the reward weights);
* ``episode``: the scenario of one episode, chosen from named streams of its seed;
* ``rewards``: the weighted reward components;
* ``spaces``: the Gymnasium spaces of observations, actions and the privileged state;
* ``stepping``: one episode, stepped to the robots' decision points;
* ``parallel``: :class:`~mresim_phys.learn.parallel.MresimParallelEnv` (PettingZoo);
* ``single``: :class:`~mresim_phys.learn.single.MresimEnv` (Gymnasium, one learning robot).

docs/learning.md is the reference.
"""
