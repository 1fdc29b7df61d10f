"""The ``policy`` strategy (phase 4, decide): decisions from a trained policy, or from a
learning environment (``mresim_phys.learn``).

What a policy sees is built here from the robot's :class:`~mresim_phys.strategies.base.RobotView`
alone (never the truth): the candidate targets it may choose among (``candidates``), its
observation (``observe``), how an action becomes a path (``actions``) and where a trained
policy is loaded from (``loaders``). docs/learning.md describes each array.
"""
