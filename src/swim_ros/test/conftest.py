import pytest

from swim_ros.domains import claim_ros_domain


@pytest.fixture(scope="session")
def ros_domain():
    return claim_ros_domain()


@pytest.fixture()
def rclpy_context(ros_domain):
    import rclpy
    context = rclpy.Context()
    rclpy.init(context=context)
    yield context
    rclpy.shutdown(context=context)
