#!/usr/bin/env python3
# SPDX-License-Identifier: GPL-3.0-or-later
"""Writes the tiny seed inputs of the fuzz targets into fuzz/corpus/<target>/.

FuzzedDataProvider takes integers (sizes, modes) from the END of the input and byte runs from
the front, so each seed is laid out as: payload bytes, then the header bytes in reverse order of
consumption. Run again after changing a target's input layout. (corpus/fuzz_image/grey16x16.jpg is
the same 16 x 16 texture as the PNG, written once by OpenCV's JPEG encoder at quality 80.)
"""
import math
import pathlib
import random
import struct
import zlib

HERE = pathlib.Path(__file__).resolve().parent


def tail(*values):
    """Header integers, each given as (value, byte count), in the order the target consumes them."""
    out = bytearray()
    for value, count in values:
        out += value.to_bytes(count, "big")  # first consumed byte = most significant
    return bytes(reversed(out))


def png(width, height, pixel, channels=1):
    """An 8-bit grey (channels 1) or RGB (3) PNG with pixel(x, y) in 0..255 in every channel, each
    row with one of the five filters (RGB: the decoders' fast path)."""
    def row(y):
        samples = bytes(pixel(x, y) for x in range(width) for _ in range(channels))
        if channels == 1:
            return b"\0" + samples
        kind = y % 5
        out = bytearray([kind])
        for i, value in enumerate(samples):
            a = samples[i - channels] if i >= channels else 0
            b = rows[y - 1][i] if y > 0 else 0
            c = rows[y - 1][i - channels] if y > 0 and i >= channels else 0
            p = a + b - c
            paeth = a if abs(p - a) <= abs(p - b) and abs(p - a) <= abs(p - c) else b if abs(p - b) <= abs(p - c) else c
            predictor = [0, a, b, (a + b) // 2, paeth][kind]
            out.append((value - predictor) & 255)
        rows.append(samples)
        return bytes(out)

    rows = []
    raw = b"".join(row(y) for y in range(height))

    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))

    header = struct.pack(">IIBBBBB", width, height, 8, 0 if channels == 1 else 2, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw, 9))
            + chunk(b"IEND", b""))


def texture(x, y):
    return int(127 + 60 * math.sin(0.7 * x) * math.cos(0.5 * y) + 60 * math.sin(0.23 * (x + 2 * y))) & 255


def write(target, name, data):
    folder = HERE / "corpus" / target
    folder.mkdir(parents=True, exist_ok=True)
    (folder / name).write_bytes(data)


def image_seeds():
    write("fuzz_image", "grey16x16.png", png(16, 16, texture))
    write("fuzz_image", "rgb21x9.png", png(21, 9, texture, channels=3))
    noise = bytes(random.Random(1).randrange(256) for _ in range(256))
    # Raw images: type index (0..5 = 8UC1, 8UC3, 8UC4, 16UC1, 32FC1, 64FC1), cols - 1, rows - 1.
    write("fuzz_image", "raw_8uc1_40x30", noise + tail((0, 1), (39, 2), (29, 2)))
    write("fuzz_image", "raw_8uc3_70x90", noise + tail((1, 1), (69, 2), (89, 2)))
    floats = struct.pack("<8f", 0.1, 0.9, float("nan"), 0.4, float("inf"), 0.2, -1.0, 0.7)
    write("fuzz_image", "raw_32fc1_nan_inf", floats + tail((4, 1), (63, 2), (63, 2)))


def image_pair_seeds():
    pixels = bytes(texture(x, y) for y in range(16) for x in range(16))
    # Mode 2: the newer frame is the older rotated by 10 deg, zoomed 1.05 and shifted (3, -2).
    write("fuzz_image_pair", "warped", pixels + tail((2, 1), (190, 2), (35, 1), (23, 1), (18, 1)))
    write("fuzz_image_pair", "bytes", pixels + pixels[::-1] + tail((0, 1)))
    floats = struct.pack("<4f", 0.5, float("nan"), 0.25, float("-inf"))
    write("fuzz_image_pair", "floats", floats + floats[::-1] + tail((1, 1)))


def cam_param_seeds():
    write("fuzz_cam_param", "cam_param.yaml", b"""%YAML:1.0

Camera.type: "PinHole"

Camera.fx: 2950.5
Camera.fy: 2948.0
Camera.cx: 2020.0
Camera.cy: 1512.5

Camera.k1: 0.15
Camera.k2: -0.31
Camera.p1: -0.0007
Camera.p2: 0.005

Camera.width: 4056
Camera.height: 3040""")
    write("fuzz_cam_param", "cam_param_no_header.yaml",
          b"Camera.fx: 500\nCamera.fy: 500\nCamera.cx: 320\nCamera.cy: 240\n")
    # Lenses for the undistortion: a rational one of the images' size, and one that folds over.
    write("fuzz_cam_param", "lens_rational.yaml",
          b"Camera.fx: 60\nCamera.fy: 61\nCamera.cx: 40.5\nCamera.cy: 29\nCamera.k1: -0.3\n"
          b"Camera.k2: 0.1\nCamera.k3: 0.01\nCamera.k4: 0.05\nCamera.width: 80\nCamera.height: 60\n")
    write("fuzz_cam_param", "lens_folding.yaml",
          b"Camera.fx: 60\nCamera.fy: 60\nCamera.cx: 40\nCamera.cy: 30\nCamera.k1: -5\n")
    write("fuzz_cam_param", "config.yaml", b"""%YAML 1.0
---
mode: efmt
initial_altitude: 12.5
camera_fx: 450.0
registration:
  size: 128
  block_radius: 3
matching:
  shift_range: 20.0
tracking:
  max_failed_frames: 2
""")


def energy_vector_seeds():
    def peaks(n, centres):
        return [min(255, int(sum(200 * math.exp(-0.5 * ((j - c) / 1.5) ** 2) for c in centres)) + 1)
                for j in range(n)]

    # Byte mode (bool false), equal lengths: T-like vectors, b stretched by 1.5 from a.
    a, b = peaks(64, [10, 20]), peaks(64, [15, 30])
    write("fuzz_energy_vectors", "stretch", tail((0, 1), (64, 2), (1, 1), *((v, 1) for v in a + b)))
    # Zoom-like vectors shifted by 3 bins.
    a, b = peaks(48, [20]), peaks(48, [23])
    write("fuzz_energy_vectors", "shift", tail((0, 1), (48, 2), (1, 1), *((v, 1) for v in a + b)))
    # Raw floats (bool true) with NaN, inf and a negative value, length 8.
    words = [struct.unpack("<I", struct.pack("<f", x))[0]
             for x in (1.0, float("nan"), 4.0, float("inf"), -2.0, 0.5, 3.0, 0.0)]
    write("fuzz_energy_vectors", "raw_floats",
          tail((1, 1), (8, 2), (1, 1), *((w, 4) for w in words + words[::-1])))


if __name__ == "__main__":
    image_seeds()
    image_pair_seeds()
    cam_param_seeds()
    energy_vector_seeds()
