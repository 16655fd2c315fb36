#!/usr/bin/python3
# SPDX-License-Identifier: GPL-3.0-or-later
"""rostest checker: feeds the odometry node bad input between good frames and checks that it
survives, never publishes a non-finite value or a zero variance, rejects what it cannot use (and
counts it in /diagnostics), and tracks again when good frames return.

Bad input: an unsupported encoding, black and NaN frames, a duplicate and an out-of-order stamp,
a change of image size, a corrupt compressed-looking payload in a raw message (wrong step), a
tiny frame (40 x 30: refused), a full-resolution 4056 x 3040 camera frame (a restart), and
camera_info with a fisheye model, a non-finite and a folding distortion (frames refused, the
problem named in /diagnostics) before a usable distorted one.
"""
import math
import sys
import threading
import time
import unittest

import numpy as np
import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray
from nav_msgs.msg import Odometry
from sensor_msgs.msg import CameraInfo, Image


def texture(size, seed):
    """Smooth random texture (sum of upsampled noise octaves), values 0..255."""
    rng = np.random.default_rng(seed)
    out = np.zeros((size, size))
    cell = 64
    while cell >= 2:
        grid = rng.standard_normal((size // cell + 2, size // cell + 2))
        up = np.kron(grid, np.ones((cell, cell)))[:size, :size]
        out += up * cell ** 0.5
        cell //= 2
    out -= out.min()
    return (255 * out / out.max()).astype(np.uint8)


class BadInputCheck(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("bad_input_check")
        cls.odometry, cls.diagnostics = [], []
        cls.lock = threading.Lock()
        rospy.Subscriber("/odom", Odometry, lambda m: cls.store(cls.odometry, m), queue_size=100)
        rospy.Subscriber("/diagnostics", DiagnosticArray, lambda m: cls.store(cls.diagnostics, m), queue_size=20)
        cls.images = rospy.Publisher("/camera/image_raw", Image, queue_size=5)
        cls.info = rospy.Publisher("/camera/camera_info", CameraInfo, queue_size=5, latch=True)
        cls.scene = texture(1024, 5)
        cls.stamp = 100.0
        deadline = time.time() + 30.0
        while cls.images.get_num_connections() == 0 and time.time() < deadline:
            time.sleep(0.1)
        cls.publish_info(256)
        cls.run_sequence()

    @classmethod
    def store(cls, target, message):
        with cls.lock:
            target.append(message)

    @classmethod
    def publish_info(cls, size, model="", D=()):
        info = CameraInfo()
        info.width = info.height = size
        info.K = [0.8 * size, 0, size / 2 - 0.5, 0, 0.8 * size, size / 2 - 0.5, 0, 0, 1]
        info.distortion_model = model
        info.D = list(D)
        info.header.frame_id = "camera_optical"
        cls.info.publish(info)
        time.sleep(0.3)

    @classmethod
    def send(cls, data, encoding, stamp=None, step=None):
        message = Image()
        message.header.stamp = rospy.Time.from_sec(cls.stamp if stamp is None else stamp)
        message.header.frame_id = "camera_optical"
        message.height, message.width = data.shape[:2]
        message.encoding = encoding
        message.step = step if step is not None else data.strides[0]
        message.data = data.tobytes()
        cls.images.publish(message)
        time.sleep(0.25)  # slow enough that nothing is dropped: every frame is judged

    @classmethod
    def good(cls, k, size=256):
        x = 200 + 12 * k
        cls.stamp += 0.2
        cls.send(np.ascontiguousarray(cls.scene[300:300 + size, x:x + size]), "mono8")

    @classmethod
    def run_sequence(cls):
        k = 0
        for _ in range(4):
            cls.good(k)
            k += 1
        cls.count_before_bad = len(cls.odometry)
        cls.stamp += 0.2
        cls.send(np.zeros((256, 256, 2), np.uint8), "8UC2")             # unsupported encoding
        for _ in range(3):                                              # lens cap: black frames
            cls.stamp += 0.2
            cls.send(np.zeros((256, 256), np.uint8), "mono8")
        for _ in range(2):                                              # NaN frames
            cls.stamp += 0.2
            cls.send(np.full((256, 256), np.nan, np.float32), "32FC1")
        cls.send(np.zeros((256, 256), np.uint8), "mono8", stamp=cls.stamp)          # duplicate
        cls.send(np.zeros((256, 256), np.uint8), "mono8", stamp=cls.stamp - 0.1)    # reordered
        cls.stamp += 0.2
        cls.send(np.zeros((256, 256), np.uint8), "mono8", step=100)     # inconsistent step
        cls.stamp += 0.2
        cls.send(np.full((30, 40), 128, np.uint8), "mono8")             # tiny: refused
        cls.stamp += 0.2
        big = np.ascontiguousarray(np.kron(cls.scene[:304, :406], np.ones((10, 10), np.uint8))[:3040, :4056])
        cls.send(big, "mono8")                                          # 4056 x 3040: restart
        time.sleep(1.0)  # a 12 MB frame: give it time before the next
        for _ in range(4):                                              # texture returns
            cls.good(k)
            k += 1
        cls.publish_info(200)
        for _ in range(5):                                              # new image size
            cls.good(k, size=200)
            k += 1
        cls.count_before_bad_info = len(cls.odometry)
        for model, D in (("equidistant", [0.1, 0.01, 0.0, 0.0]),        # fisheye: not a pinhole
                         ("plumb_bob", [float("nan"), 0.0, 0.0, 0.0, 0.0]),
                         ("plumb_bob", [-5.0, 0.0, 0.0, 0.0, 0.0])):    # folds over: no inverse
            cls.publish_info(200, model, D)
            for _ in range(2):
                cls.good(k, size=200)
                k += 1
            time.sleep(1.2)  # a diagnostics period names the problem
        cls.count_after_bad_info = len(cls.odometry)
        cls.publish_info(200, "plumb_bob", [-0.1, 0.01, 0.0, 0.0, 0.0])  # a real lens again
        for _ in range(4):
            cls.good(k, size=200)
            k += 1
        time.sleep(2.5)  # a diagnostics period

    def test_node_keeps_publishing_after_bad_input(self):
        with self.lock:
            count = len(self.odometry)
        self.assertGreater(self.count_before_bad, 0)
        self.assertGreaterEqual(count, self.count_before_bad + 5, "odometry stopped after bad input")

    def test_nothing_non_finite_and_no_zero_variance(self):
        with self.lock:
            messages = list(self.odometry)
        for m in messages:
            p, q = m.pose.pose.position, m.pose.pose.orientation
            for value in (p.x, p.y, p.z, q.x, q.y, q.z, q.w):
                self.assertTrue(math.isfinite(value))
            for i in range(6):
                self.assertTrue(math.isfinite(m.pose.covariance[i * 7]))
                self.assertGreater(m.pose.covariance[i * 7], 0.0)

    def test_unusable_camera_info_is_named_and_survived(self):
        with self.lock:
            statuses = [s for a in self.diagnostics for s in a.status if "odometry" in s.name]
            count = len(self.odometry)
        problems = [kv.value for s in statuses for kv in s.values if kv.key == "last problem"]
        for part in ("distortion model 'equidistant' is not supported",
                     "distortion coefficients (D) are not finite",
                     "lens distortion (k1 -5) cannot be undone"):
            self.assertTrue(any(part in p for p in problems), f"no '{part}' in {sorted(set(problems))}")
        self.assertTrue(all("\n" not in p for p in problems))
        self.assertEqual(self.count_after_bad_info, self.count_before_bad_info,
                         "frames of an unusable camera_info were registered")
        self.assertGreaterEqual(count, self.count_after_bad_info + 3, "odometry did not resume")

    def test_rejections_are_counted(self):
        with self.lock:
            statuses = [s for a in self.diagnostics for s in a.status if "odometry" in s.name]
        self.assertTrue(statuses)
        values = {kv.key: kv.value for kv in statuses[-1].values}
        # unsupported encoding, duplicate, reordered, wrong step, tiny
        self.assertGreaterEqual(int(values["frames rejected (stamp, encoding, intrinsics)"]), 5, values)


if __name__ == "__main__":
    rostest.rosrun("oefmt", "bad_input_check", BadInputCheck, sys.argv)
