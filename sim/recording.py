"""What a recording of a simulated run adds: the ground truth, injected faults and other
simulator events, the navigation map with its marks, and the lidar's mounting.

The runtime's recorder never imports the simulator; the CLI hands it these hooks.
"""

from __future__ import annotations

from bt_runtime.runtime.recording import MapSnapshot, RecordingHooks, StreamSpec

from .driver import SimDriver

GROUND_TRUTH, FAULTS, EVENTS = "/sim/ground_truth", "/sim/faults", "/sim/events"
GROUND_TRUTH_POSE = GROUND_TRUTH + "/pose"  # the same pose as PoseStamped: what Foxglove's 3D panel draws


def recording_hooks(driver: SimDriver, *, ground_truth: str = GROUND_TRUTH, faults: str = FAULTS,
                    events: str = EVENTS, ground_truth_pose: str = GROUND_TRUTH_POSE) -> RecordingHooks:
    costmap = driver.navigation.global_costmap
    grid = driver.map

    def snapshot() -> MapSnapshot:
        """The map the planner uses: the static map plus the persistent marks (add_obstacle)."""
        data = grid.data.copy()
        data[costmap.updates] = 100
        return MapSnapshot(data, grid.resolution, grid.origin)

    def map_source():
        return costmap.base_version, snapshot

    lidar = driver.sim.profile.lidar
    truth = driver.sim.subscribe
    return RecordingHooks(
        # the simulator's own topics: not on the driver interface (the robot never gets the truth)
        streams=[StreamSpec("ground_truth", ground_truth, "odometry", source=truth, pose_topic=ground_truth_pose),
                 StreamSpec("sim_event", faults, "event", select=lambda e: e.kind == "fault", source=truth),
                 StreamSpec("sim_event", events, "event", select=lambda e: e.kind != "fault", source=truth)],
        map_source=map_source,
        laser_offset=(lidar.x, lidar.y, 0.0))
