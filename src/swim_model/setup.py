from setuptools import find_packages, setup

package_name = 'swim_model'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        ('share/' + package_name + '/config', ['swim_model/config/rig.yaml']),
    ],
    package_data={package_name: ['config/*.yaml', 'py.typed']},
    install_requires=['setuptools', 'numpy', 'scipy', 'casadi', 'numba', 'pyyaml', 'matplotlib'],
    zip_safe=True,
    maintainer='swim maintainers',
    maintainer_email='swim@example.com',
    description=("The swimming machine's physics: Joukowski foil added mass and the 4-DOF/3-DOF "
                 "vehicle model (pure Python, no ROS)."),
    license='Apache-2.0',
    tests_require=['pytest'],
    entry_points={
        'console_scripts': [
            'swim-model-demo = swim_model.demo:main'
        ],
    },
)
