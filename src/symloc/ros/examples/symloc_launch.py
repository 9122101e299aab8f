"""ROS 2 launch file for the symloc node on a robot (e.g. a TurtleBot3 with nav2's map_server).

    ros2 launch symloc_launch.py params:=/path/to/symloc_params.yaml namespace:=robot1

The node is the ``symloc`` console command, started as a process; topics are remapped here to
the robot's names. symloc does not broadcast the map -> odom transform (tf2_msgs is not on
PyPI); a robot that needs it can derive it from ``amcl_pose`` and odometry.
"""

from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, ExecuteProcess
from launch.substitutions import LaunchConfiguration


def generate_launch_description() -> LaunchDescription:
    params = LaunchConfiguration("params")
    namespace = LaunchConfiguration("namespace")
    return LaunchDescription(
        [
            DeclareLaunchArgument("params", description="symloc parameters YAML"),
            DeclareLaunchArgument("namespace", default_value="/"),
            ExecuteProcess(
                cmd=[
                    "symloc",
                    "ros",
                    "node",
                    "--params",
                    params,
                    "--ros-args",
                    "-r",
                    ["__ns:=", namespace],
                    "-r",
                    "scan:=scan",
                    "-r",
                    "camera/image_raw:=camera/image_raw",
                ],
                output="screen",
            ),
        ]
    )
