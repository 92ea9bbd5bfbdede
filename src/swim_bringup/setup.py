from glob import glob

from setuptools import find_packages, setup

package_name = 'swim_bringup'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    package_data={package_name: ['py.typed']},
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        ('share/' + package_name + '/config', glob('config/*.yaml')),
        ('share/' + package_name + '/config/paper', glob('config/paper/*.yaml')),
        ('share/' + package_name + '/launch', glob('launch/*.launch.*')),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='swim maintainers',
    maintainer_email='swim@example.com',
    description='Bring-up of the closed loop (simulator or bridge, planner, tracker), recording, analysis, demo.',
    license='Apache-2.0',
    tests_require=['pytest'],
    entry_points={
        'console_scripts': [
            'swim-demo = swim_bringup.demo:main',
            'swim-analyze = swim_bringup.analysis:main',
            'swim-experiments = swim_bringup.experiments:main',
            'swim-record = swim_bringup.record:main',
            'swim-bringup = swim_bringup.bringup:main',
            'swim-maneuver = swim_bringup.maneuver_cli:main',
            'maneuver_node = swim_bringup.maneuver_node:main',
        ],
    },
)
