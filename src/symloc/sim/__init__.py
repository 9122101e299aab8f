"""The embedded simulated world: rooms, lidar, odometry, camera."""
