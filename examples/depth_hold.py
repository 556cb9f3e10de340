#!/usr/bin/python3
"""Depth hold of a tethered BlueROV2 Heavy in Python: a PID on the depth drives the four
vertical thrusters, with the tether's vertical pull on the vehicle fed forward (read from
sim.tether(...).reactions each step).

    python3 examples/depth_hold.py [MODEL.xml] [--duration S] [--bound M] [--depth D]

MODEL.xml defaults to bluerov2_heavy.xml in mjtether.models_dir. Prints, once a second, the
time, depth [m], the tension at the vehicle [N] and the thrust [N]; exits 0 if the depth stayed
within --bound [m] of the set-point after the first 5 s, 1 if not (docs/python.md).
"""
import argparse
import os
import sys

import numpy as np

import mjtether

VERTICAL = ("vfr", "vfl", "vrr", "vrl")  # thrusters along the body z-axis, 40 N each at most


class Pid:
    """PID on an error and its rate (from the measured velocity), with a clamped integral."""

    def __init__(self, kp, ki, kd, integral_limit):
        self.kp, self.ki, self.kd, self.limit = kp, ki, kd, integral_limit
        self.integral = 0.0

    def __call__(self, error, rate, dt):
        self.integral = float(np.clip(self.integral + self.ki * error * dt, -self.limit, self.limit))
        return self.kp * error + self.integral + self.kd * rate


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("model", nargs="?",
                        default=os.path.join(mjtether.models_dir, "bluerov2_heavy.xml"))
    parser.add_argument("--duration", type=float, default=30.0, help="simulated time [s]")
    parser.add_argument("--bound", type=float, default=0.1, help="allowed depth error [m]")
    parser.add_argument("--depth", type=float, default=None,
                        help="set-point, world z [m] (default: the initial depth)")
    args = parser.parse_args()

    try:
        sim = mjtether.Simulation(args.model)
        rov = sim.body("rov")
        tether = sim.tether("umbilical")
        vertical = [sim.actuator_id(name) for name in VERTICAL]
    except (mjtether.Error, KeyError) as e:
        print(f"depth_hold: {e}", file=sys.stderr)
        return 2

    # Heave: m + A3 = 26 kg at 1.5 rad/s, critically damped (as examples/rov_controller.h);
    # the integral takes up the net buoyancy.
    pid = Pid(kp=60.0, ki=20.0, kd=80.0, integral_limit=40.0)
    setpoint = rov.pos[2] if args.depth is None else args.depth
    h = sim.timestep
    ctrl = sim.ctrl  # a view: writing it sets MuJoCo's controls
    worst = 0.0
    print("time,depth,tension,thrust")
    while sim.time < args.duration:
        z, vz = rov.pos[2], sim.qvel[2]  # free joint: world-frame linear velocity first
        pull_z = tether.reactions["force_b"][2]  # [N] the tether's vertical pull on the ROV
        thrust = pid(setpoint - z, -vz, h) - pull_z
        ctrl[vertical] = np.clip(thrust / 4, -40.0, 40.0)
        sim.step()  # the boat's motion: schedule, then mj_step
        if sim.time > 5:
            worst = max(worst, abs(rov.pos[2] - setpoint))
        if round(sim.time / h) % round(1 / h) == 0:
            print(f"{sim.time:.0f},{rov.pos[2]:.4f},{tether.reactions['tension_b']:.2f},"
                  f"{thrust:.2f}")
    print(f"largest depth error after 5 s: {worst:.4f} m (bound {args.bound} m)")
    return 0 if worst <= args.bound else 1


if __name__ == "__main__":
    sys.exit(main())
