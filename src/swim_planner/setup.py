from setuptools import find_packages, setup

package_name = 'swim_planner'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
    ],
    install_requires=['setuptools', 'numpy', 'scipy', 'casadi', 'tqdm'],
    package_data={package_name: [f'library/{folder}/{files}' for folder in ('default', 'circulatory')
                                  for files in ('manifest.json', 'primitives/*.npz')] + ['py.typed']},
    zip_safe=True,
    maintainer='swim maintainers',
    maintainer_email='swim@example.com',
    description=('Off-line optimal-control motion primitives, the primitive library, the '
                 'lane/energy graph and the maneuver planner node.'),
    license='Apache-2.0',
    tests_require=['pytest'],
    entry_points={
        'console_scripts': [
            'swim-primitives = swim_planner.cli:main',
            'planner_node = swim_planner.planner_node:main',
        ],
    },
)
