"""flatsim: a 2D physics stand-in for Gazebo that speaks gazebo_ros's topics."""
