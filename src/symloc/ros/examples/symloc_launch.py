"""ROS 2 launch file for the symloc node on a robot (e.g. a TurtleBot3 with nav2's map_server).

    ros2 launch symloc_launch.py params:=/path/to/symloc_params.yaml namespace:=robot1

The node is the ``symloc`` console command, started as a process and activated at once
(``--autostart``; under nav2, its lifecycle manager activates it instead: see the README's
"A drop-in for nav2_amcl"); topics are remapped here to the robot's names. Run
``symloc ros setup`` once: it builds tf2_msgs (map -> odom, odometry from /tf) and the rest.
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
                    "--autostart",
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
