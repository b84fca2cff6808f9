from rosbridge_app.collector.modes import ModeDecider


def test_auto_returns_only_after_the_last_joystick_command_times_out():
    d = ModeDecider(timeout=0.5)
    assert d.navigation(0.0) == "auto"
    # The operator drives for 2 s while navigation keeps sending.
    for i in range(21):
        t = 0.1 + i * 0.1
        assert d.joystick(True, t) == "ito"
        assert d.navigation(t + 0.05) == "ito"  # never flips back while driving
    assert d.navigation(2.3) == "ito"  # 0.2 s after the last joystick command
    assert d.navigation(2.7) == "auto"


def test_released_stick_does_not_keep_manual_alive():
    d = ModeDecider(timeout=0.5)
    d.joystick(True, 0.0)
    d.joystick(False, 0.4)  # zero twist: the operator let go
    assert d.navigation(0.6) == "auto"
