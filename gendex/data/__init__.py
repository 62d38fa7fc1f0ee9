"""Episodes and their exports: LeRobot v3.0 datasets and ManiSkill-style HDF5 trajectories."""
