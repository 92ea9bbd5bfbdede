from setuptools import find_packages, setup

package_name = 'swim_hw_bridge'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        ('share/' + package_name + '/config', ['swim_hw_bridge/config/bridge.yaml']),
    ],
    package_data={package_name: ['config/*.yaml', 'py.typed']},
    install_requires=['setuptools', 'numpy', 'pyyaml'],
    zip_safe=True,
    maintainer='swim maintainers',
    maintainer_email='swim@example.com',
    description='The motor/encoder hardware bridge node and its safety layer.',
    license='Apache-2.0',
    tests_require=['pytest'],
    entry_points={
        'console_scripts': [
            'bridge_node = swim_hw_bridge.bridge_node:main',
        ],
    },
)
