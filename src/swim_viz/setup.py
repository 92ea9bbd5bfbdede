from setuptools import find_packages, setup

package_name = 'swim_viz'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    package_data={package_name: ['py.typed']},
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='swim maintainers',
    maintainer_email='swim@example.com',
    description='The rig in RViz and Foxglove: URDF from the rig file, /tf from joint_states, path markers.',
    license='Apache-2.0',
    tests_require=['pytest'],
    entry_points={
        'console_scripts': [
            'rig_state_publisher = swim_viz.rig_state_publisher:main',
            'marker_node = swim_viz.marker_node:main',
            'foxglove_node = swim_viz.foxglove_node:main',
        ],
    },
)
