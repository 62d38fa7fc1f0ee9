"""Solving tasks: inverse kinematics, motion planning, grasp synthesis and the stage executor (issue 4, in progress)."""
