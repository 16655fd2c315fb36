#!/usr/bin/python3
# SPDX-License-Identifier: GPL-3.0-or-later
"""rostest checker: floods the odometry node with textured 512x512 images at ~/rate Hz for
~/duration seconds and checks that it survives, keeps publishing odometry at its processing
rate, counts the drops in /diagnostics and does not grow in memory (resident set growth after
the warm-up below ~/max_growth_mb)."""
import sys
import threading
import time
import unittest
import xmlrpc.client

import numpy as np
import rosgraph
import rosnode
import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray
from nav_msgs.msg import Odometry
from sensor_msgs.msg import CameraInfo, Image


def node_pid(name):
    api = rosnode.get_api_uri(rosgraph.Master("/load_check"), name)
    code, _, pid = xmlrpc.client.ServerProxy(api).getPid("/load_check")
    if code != 1:
        raise RuntimeError(f"cannot get the pid of {name}")
    return pid


def resident_mb(pid):
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    raise RuntimeError("no VmRSS")


class LoadCheck(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("load_check")
        cls.rate = float(rospy.get_param("~rate", 200.0))
        cls.duration = float(rospy.get_param("~duration", 60.0))
        cls.max_growth_mb = float(rospy.get_param("~max_growth_mb", 10.0))
        cls.node = rospy.get_param("~node", "/oefmt_manager")
        cls.odometry_count = 0
        cls.diagnostics = []
        cls.lock = threading.Lock()
        rospy.Subscriber("/odom", Odometry, cls.on_odometry, queue_size=1000)
        rospy.Subscriber("/diagnostics", DiagnosticArray, cls.on_diagnostics, queue_size=20)
        images = rospy.Publisher("/camera/image_raw", Image, queue_size=1)
        info = rospy.Publisher("/camera/camera_info", CameraInfo, queue_size=1, latch=True)
        camera = CameraInfo(width=512, height=512)
        camera.K = [400.0, 0, 255.5, 0, 400.0, 255.5, 0, 0, 1]
        info.publish(camera)
        deadline = time.time() + 30
        while images.get_num_connections() == 0 and time.time() < deadline:
            time.sleep(0.1)
        rng = np.random.default_rng(1)
        scene = (rng.random((96, 192)) * 255).astype(np.uint8)
        scene = np.kron(scene, np.ones((8, 8), np.uint8))  # 768 x 1536 blocky texture
        pid = node_pid(cls.node)
        cls.memory = []
        start = time.time()
        sent = 0
        while time.time() - start < cls.duration and not rospy.is_shutdown():
            x = (sent * 3) % 1000
            message = Image(height=512, width=512, encoding="mono8", step=512)
            message.header.stamp = rospy.Time.now()
            message.header.frame_id = "camera_optical"
            message.data = scene[100:612, x:x + 512].tobytes()
            images.publish(message)
            sent += 1
            elapsed = time.time() - start
            if sent % int(cls.rate) == 0:
                cls.memory.append((elapsed, resident_mb(pid)))
            time.sleep(max(0.0, sent / cls.rate - (time.time() - start)))
        cls.sent = sent
        cls.elapsed = time.time() - start
        time.sleep(2.5)
        cls.alive = True
        try:
            resident_mb(pid)
        except (OSError, RuntimeError):
            cls.alive = False

    @classmethod
    def on_odometry(cls, _):
        with cls.lock:
            cls.odometry_count += 1

    @classmethod
    def on_diagnostics(cls, message):
        with cls.lock:
            cls.diagnostics.append(message)

    def test_survives_and_publishes(self):
        self.assertTrue(self.alive)
        rate_in = self.sent / self.elapsed
        rate_out = self.odometry_count / self.elapsed
        rospy.loginfo(f"load: sent {self.sent} images at {rate_in:.0f} Hz, odometry at {rate_out:.1f} Hz")
        self.assertGreater(rate_in, 0.5 * self.rate, "the publisher could not keep the rate")
        self.assertGreater(rate_out, 5.0, "odometry stopped under load")

    def test_drops_are_counted(self):
        with self.lock:
            statuses = [s for a in self.diagnostics for s in a.status if "odometry" in s.name]
        self.assertTrue(statuses)
        values = {kv.key: kv.value for kv in statuses[-1].values}
        self.assertGreater(int(values["frames dropped (newest wins)"]), 0, values)

    def test_memory_does_not_grow(self):
        warm = [mb for t, mb in self.memory if t >= min(10.0, self.duration / 3)]
        self.assertGreater(len(warm), 2)
        growth = max(warm) - warm[0]
        rospy.loginfo(f"load: resident {warm[0]:.1f} -> {max(warm):.1f} MB (growth {growth:.1f} MB)")
        self.assertLess(growth, self.max_growth_mb)


if __name__ == "__main__":
    rostest.rosrun("oefmt", "load_check", LoadCheck, sys.argv)
