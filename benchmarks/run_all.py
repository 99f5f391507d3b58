"""Run every benchmark in turn (``make bench``); results are copied into BENCHMARKS.md by hand."""

from __future__ import annotations

from benchmarks import (
    attack_suite,
    core_install,
    firmware_command_time,
    foxglove_live,
    goto,
    idle_phase,
    link_faults,
    link_throughput,
    lockstep_tick,
    log_cost,
    mapping_localise,
    mapping_mapper,
    motor_model,
    move_landing,
    odometry_drift,
    planner,
    ros2_latency,
    ros2_rates,
    scan_matching,
    scanner_cost,
    seed002_run,
    sim_speed,
    slam_synthetic,
    sonar_stop,
    speed_accuracy,
    startup,
    tracking,
    uno_command_cycles,
    uno_encoder_counts,
)


def main() -> int:
    for title, run in (
        ("simulator speed", lambda: sim_speed.main([])),
        ("a lockstep tick's CPU (client, link, firmware, simulator)", lambda: lockstep_tick.main([])),
        ("start-up: --help, robot list, first HELLO cold and warm", lambda: startup.main([])),
        ("core install: size and import time of `pip install omnibot`", lambda: core_install.main([])),
        ("laser scanner cost", lambda: scanner_cost.main([])),
        ("firmware time per command", lambda: firmware_command_time.main([])),
        ("UNO firmware cycles per command (simavr)", lambda: uno_command_cycles.main([])),
        (
            "UNO encoder counts through reversals (simavr, physics in the loop)",
            lambda: uno_encoder_counts.main([]),
        ),
        ("line throughput, lockstep", lambda: link_throughput.main([])),
        ("line throughput, pty emulator", lambda: link_throughput.main(["--pty"])),
        (
            "line throughput, pty emulator, 2 busy processes beside",
            lambda: link_throughput.main(["--pty", "--load", "2"]),
        ),
        ("link faults", lambda: link_faults.main([])),
        ("attack and fault suite (issue 27; `--quick` for a smoke run)", lambda: attack_suite.main([])),
        (
            "motor model: the acceptance robot on carpet, true motors",
            lambda: motor_model.main(["--map", "model"]),
        ),
        ("axis MOVEs against the idle wheels' phase: nominal omni4 on carpet", lambda: idle_phase.main([])),
        ("where MOVE, ROTATE and DELTA land", lambda: move_landing.main([])),
        ("speed accuracy, open loop", lambda: speed_accuracy.main(["--open-loop"])),
        ("speed accuracy, on the wheel-speed loop", lambda: speed_accuracy.main([])),
        ("speed accuracy, with the floor's slip", lambda: speed_accuracy.main(["--slip"])),
        ("path tracking", lambda: tracking.main([])),
        ("seed 002's run: up to 5 m/s on its S, taught and repeated", lambda: seed002_run.main([])),
        ("odometry drift", lambda: odometry_drift.main([])),
        ("sonar stop", lambda: sonar_stop.main([])),
        ("occupancy mapper: ray walk and rebuilds", lambda: mapping_mapper.main([])),
        ("localisation in a saved map", lambda: mapping_localise.main([])),
        ("scan matching: ours, small_gicp, kiss-icp", lambda: scan_matching.main([])),
        ("SLAM on synthetic scans, 100 m", lambda: slam_synthetic.main([])),
        ("path planning: grid A* against OMPL", lambda: planner.main([])),
        ("goto: 20 seeded goals per robot", lambda: goto.main([])),
        ("recording cost (--log)", lambda: log_cost.main([])),
        ("Foxglove live: CPU per message", lambda: foxglove_live.main([])),
        ("ROS 2: cmd_vel -> VEL latency (private network namespace)", lambda: ros2_latency.main([])),
        (
            "ROS 2: odom rates, CPU, robots per process (private network namespace)",
            lambda: ros2_rates.main([]),
        ),
    ):
        print(f"\n== {title}")
        run()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
