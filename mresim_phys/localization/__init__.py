"""Localisation (shared): a robot's believed pose and how sure it is of it (issue 31).

``odometry`` is the motion model that makes a robot's true pose drift from the pose its
wheels report; ``estimate`` carries the believed pose's uncertainty and fuses
corrections into it.
"""
