"""The studio: Gazebo's window as a web page, served by the running simulator.

world (what the studio reads from a Simulation and asks of the simulator),
protocol (commands and their fields), hub (sessions, commands and the stream),
server (HTTP and WebSocket on loopback, behind a per-run token), address
(where gzclient finds the page of the current ROS master) and chase (what the chase view
shows: a camera image's ball pixels by third, and the drive commands). No ROS here.
"""
