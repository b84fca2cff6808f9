"""A robot team's interface packages stay built: the setup remembers
FTT_ROS_INTERFACES, so a later setup (every ``scripts/run.sh``) started without
the variable neither rebuilds nor drops them."""

import os
import subprocess
import sys

import pytest

from tests.support.ros import ROOT, requires_ros

pytestmark = [pytest.mark.ros, requires_ros]


def test_a_later_setup_without_the_variable_keeps_the_teams_packages(robot_interfaces, tmp_path):
    prefix = robot_interfaces["AMENT_PREFIX_PATH"].split(os.pathsep)[0]
    env = {k: v for k, v in os.environ.items() if k != "FTT_ROS_INTERFACES"}
    later = subprocess.run(
        ["bash", str(ROOT / "scripts/setup.d/50-ros-interfaces.sh")],
        cwd=tmp_path,  # elsewhere: the remembered folder is absolute
        env={**env, "FTT_ROS_PREFIX": prefix},
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert later.returncode == 0, later.stdout + later.stderr
    assert "FTT_ROS_INTERFACES from the last setup: " in later.stdout
    # Built already, or built or unpacked from the cache again with the team's
    # package (the shared test prefix may come from another checkout's folder).
    done = [
        line
        for line in later.stdout.splitlines()
        if "ROS interfaces built into" in line or "ROS interfaces unpacked from" in line
    ]
    assert "ROS interfaces: already built" in later.stdout or (
        done and "ftt_robot_msgs" in done[-1]
    ), later.stdout
    still = subprocess.run(
        [sys.executable, "-c", "import ftt_robot_msgs.msg"],
        env={**env, **robot_interfaces},
        capture_output=True,
        text=True,
    )
    assert still.returncode == 0, still.stderr
