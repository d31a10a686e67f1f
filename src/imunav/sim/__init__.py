"""Virtual sensors and trajectories."""
from imunav.sim.trajectory import Trajectory, ideal_imu
