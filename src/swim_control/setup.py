from setuptools import find_packages, setup

package_name = 'swim_control'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
    ],
    package_data={package_name: ['py.typed']},
    install_requires=['setuptools', 'numpy', 'scipy', 'casadi'],
    zip_safe=True,
    maintainer='swim maintainers',
    maintainer_email='swim@example.com',
    description=('The trajectory core the planner writes and the tracker executes: trajectory, time scaling, '
                 'Riccati gains, measures and plan errors (pure Python, no ROS).'),
    license='Apache-2.0',
    tests_require=['pytest'],
    entry_points={'console_scripts': []},
)
