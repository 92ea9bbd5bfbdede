from setuptools import find_packages, setup

package_name = 'swim_ros'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    package_data={package_name: ['py.typed']},
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        ('share/' + package_name + '/config', ['config/fastdds_large_messages.xml', 'config/fastdds_real_time.xml',
                                                   'config/fastdds_real_time_localhost.xml']),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='swim maintainers',
    maintainer_email='swim@example.com',
    description='The ROS boundary every swim node and client shares.',
    license='Apache-2.0',
    tests_require=['pytest'],
    entry_points={'console_scripts': []},
)
