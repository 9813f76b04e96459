"""What Gazebo's editors write: models, buildings and worlds, as SDF files. No ROS here."""
