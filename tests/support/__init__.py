"""Helpers shared by the tests; tests import them from here, never from each other.

- ``api``: the generic CRUD test class, the error-shape check, query counts;
- ``images``: small PNG/JPEG files;
- ``accounts``: users with a role;
- ``field_day``, ``snapshot``, ``sites``: a recorded field day, a database
  snapshot to compare, a second FTT installation in a subprocess;
- ``scenario``: the report's constructed test event with known figures;
- ``pdf``: reading generated PDFs back;
- ``ros``: rclpy helpers for tests that talk DDS;
- ``fkie``: the real recording in ../shared/fixtures;
- ``pages``: where a page loads its assets from;
- ``browser``: the simulated robot the browser tests drive.
"""
