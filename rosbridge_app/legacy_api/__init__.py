"""The original FTT's robot API, served by FTT for robots that run its node.

A robot that runs the original's ``ros2api`` (ROS 2) or Python node (ROS 1)
logs into FTT unchanged with ``params.server_address`` set to
``<host>:<port>/legacy/<robot token>``: the token in the path names the robot
account, and its vehicle decides what "Current Leg", "Current Shift" and
"Current Segment" mean. Every write goes through the services the collector
and the REST API use; docs/api.md ("Robots with the original FTT node") says
what is answered how, and which of the original's defects are not copied.
"""
