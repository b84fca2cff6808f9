"""Writes of robot data: poses, local poses, maps and images."""
