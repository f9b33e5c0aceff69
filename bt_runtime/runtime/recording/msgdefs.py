"""ROS 2 Jazzy message definitions the recording uses (from common_interfaces and rcl_interfaces,
as ``rosbags`` prints them), so a small typestore is built in milliseconds instead of loading
every ROS distribution's types (~0.5-1.5 s per process)."""

DEFINITIONS = {
    "builtin_interfaces/msg/Time": (
        'int32 sec\n'
        'uint32 nanosec\n'
    ),
    "diagnostic_msgs/msg/DiagnosticArray": (
        'std_msgs/Header header\n'
        'diagnostic_msgs/DiagnosticStatus[] status\n'
    ),
    "diagnostic_msgs/msg/DiagnosticStatus": (
        'byte OK=0\n'
        'byte WARN=1\n'
        'byte ERROR=2\n'
        'byte STALE=3\n'
        'byte level\n'
        'string name\n'
        'string message\n'
        'string hardware_id\n'
        'diagnostic_msgs/KeyValue[] values\n'
    ),
    "diagnostic_msgs/msg/KeyValue": (
        'string key\n'
        'string value\n'
    ),
    "geometry_msgs/msg/Point": (
        'float64 x\n'
        'float64 y\n'
        'float64 z\n'
    ),
    "geometry_msgs/msg/Pose": (
        'geometry_msgs/Point position\n'
        'geometry_msgs/Quaternion orientation\n'
    ),
    "geometry_msgs/msg/PoseStamped": (
        'std_msgs/Header header\n'
        'geometry_msgs/Pose pose\n'
    ),
    "geometry_msgs/msg/PoseWithCovariance": (
        'geometry_msgs/Pose pose\n'
        'float64[36] covariance\n'
    ),
    "geometry_msgs/msg/Quaternion": (
        'float64 x\n'
        'float64 y\n'
        'float64 z\n'
        'float64 w\n'
    ),
    "geometry_msgs/msg/Transform": (
        'geometry_msgs/Vector3 translation\n'
        'geometry_msgs/Quaternion rotation\n'
    ),
    "geometry_msgs/msg/TransformStamped": (
        'std_msgs/Header header\n'
        'string child_frame_id\n'
        'geometry_msgs/Transform transform\n'
    ),
    "geometry_msgs/msg/Twist": (
        'geometry_msgs/Vector3 linear\n'
        'geometry_msgs/Vector3 angular\n'
    ),
    "geometry_msgs/msg/TwistWithCovariance": (
        'geometry_msgs/Twist twist\n'
        'float64[36] covariance\n'
    ),
    "geometry_msgs/msg/Vector3": (
        'float64 x\n'
        'float64 y\n'
        'float64 z\n'
    ),
    "nav_msgs/msg/MapMetaData": (
        'builtin_interfaces/Time map_load_time\n'
        'float32 resolution\n'
        'uint32 width\n'
        'uint32 height\n'
        'geometry_msgs/Pose origin\n'
    ),
    "nav_msgs/msg/OccupancyGrid": (
        'std_msgs/Header header\n'
        'nav_msgs/MapMetaData info\n'
        'int8[] data\n'
    ),
    "nav_msgs/msg/Odometry": (
        'std_msgs/Header header\n'
        'string child_frame_id\n'
        'geometry_msgs/PoseWithCovariance pose\n'
        'geometry_msgs/TwistWithCovariance twist\n'
    ),
    "nav_msgs/msg/Path": (
        'std_msgs/Header header\n'
        'geometry_msgs/PoseStamped[] poses\n'
    ),
    "rcl_interfaces/msg/Log": (
        'uint8 DEBUG=10\n'
        'uint8 INFO=20\n'
        'uint8 WARN=30\n'
        'uint8 ERROR=40\n'
        'uint8 FATAL=50\n'
        'builtin_interfaces/Time stamp\n'
        'uint8 level\n'
        'string name\n'
        'string msg\n'
        'string file\n'
        'string function\n'
        'uint32 line\n'
    ),
    "sensor_msgs/msg/BatteryState": (
        'uint8 POWER_SUPPLY_STATUS_UNKNOWN=0\n'
        'uint8 POWER_SUPPLY_STATUS_CHARGING=1\n'
        'uint8 POWER_SUPPLY_STATUS_DISCHARGING=2\n'
        'uint8 POWER_SUPPLY_STATUS_NOT_CHARGING=3\n'
        'uint8 POWER_SUPPLY_STATUS_FULL=4\n'
        'uint8 POWER_SUPPLY_HEALTH_UNKNOWN=0\n'
        'uint8 POWER_SUPPLY_HEALTH_GOOD=1\n'
        'uint8 POWER_SUPPLY_HEALTH_OVERHEAT=2\n'
        'uint8 POWER_SUPPLY_HEALTH_DEAD=3\n'
        'uint8 POWER_SUPPLY_HEALTH_OVERVOLTAGE=4\n'
        'uint8 POWER_SUPPLY_HEALTH_UNSPEC_FAILURE=5\n'
        'uint8 POWER_SUPPLY_HEALTH_COLD=6\n'
        'uint8 POWER_SUPPLY_HEALTH_WATCHDOG_TIMER_EXPIRE=7\n'
        'uint8 POWER_SUPPLY_HEALTH_SAFETY_TIMER_EXPIRE=8\n'
        'uint8 POWER_SUPPLY_TECHNOLOGY_UNKNOWN=0\n'
        'uint8 POWER_SUPPLY_TECHNOLOGY_NIMH=1\n'
        'uint8 POWER_SUPPLY_TECHNOLOGY_LION=2\n'
        'uint8 POWER_SUPPLY_TECHNOLOGY_LIPO=3\n'
        'uint8 POWER_SUPPLY_TECHNOLOGY_LIFE=4\n'
        'uint8 POWER_SUPPLY_TECHNOLOGY_NICD=5\n'
        'uint8 POWER_SUPPLY_TECHNOLOGY_LIMN=6\n'
        'uint8 POWER_SUPPLY_TECHNOLOGY_TERNARY=7\n'
        'uint8 POWER_SUPPLY_TECHNOLOGY_VRLA=8\n'
        'std_msgs/Header header\n'
        'float32 voltage\n'
        'float32 temperature\n'
        'float32 current\n'
        'float32 charge\n'
        'float32 capacity\n'
        'float32 design_capacity\n'
        'float32 percentage\n'
        'uint8 power_supply_status\n'
        'uint8 power_supply_health\n'
        'uint8 power_supply_technology\n'
        'bool present\n'
        'float32[] cell_voltage\n'
        'float32[] cell_temperature\n'
        'string location\n'
        'string serial_number\n'
    ),
    "sensor_msgs/msg/Imu": (
        'std_msgs/Header header\n'
        'geometry_msgs/Quaternion orientation\n'
        'float64[9] orientation_covariance\n'
        'geometry_msgs/Vector3 angular_velocity\n'
        'float64[9] angular_velocity_covariance\n'
        'geometry_msgs/Vector3 linear_acceleration\n'
        'float64[9] linear_acceleration_covariance\n'
    ),
    "sensor_msgs/msg/LaserScan": (
        'std_msgs/Header header\n'
        'float32 angle_min\n'
        'float32 angle_max\n'
        'float32 angle_increment\n'
        'float32 time_increment\n'
        'float32 scan_time\n'
        'float32 range_min\n'
        'float32 range_max\n'
        'float32[] ranges\n'
        'float32[] intensities\n'
    ),
    "std_msgs/msg/Header": (
        'builtin_interfaces/Time stamp\n'
        'string frame_id\n'
    ),
    "tf2_msgs/msg/TFMessage": (
        'geometry_msgs/TransformStamped[] transforms\n'
    ),
}
