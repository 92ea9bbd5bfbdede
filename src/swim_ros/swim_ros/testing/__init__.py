"""What the tests of every swim package share, and nothing a node or a user's script imports.

- ``fixtures``: the pytest fixtures of a test that talks over DDS (``ros_domain``, ``rclpy_context``), the
  ``running_node`` context manager that starts the node under test as a user would, and the timeouts they wait by.
  A package's ``test/conftest.py`` imports the fixtures by name (``from swim_ros.testing.fixtures import
  ros_domain, rclpy_context  # noqa: F401``).
- ``fuzz``: the hypothesis strategies and settings of the DDS fuzz tests (``test_fuzz_*.py``).
- ``processes``: the processes a test started, found by a tag in their environment whatever their parent, and
  those left after a stop, killed.
- ``browser``: a real browser in a test: a folder served on loopback, headless Chromium reading a page's elements
  through the DevTools protocol, and swim_viz's page that shows the latest message of a Foxglove WebSocket topic.
"""
