"""Portable Float Map reading and writing for the Mitsuba reference scripts (numpy arrays of
shape (H, W, 3), row 0 = top; files little-endian, rows bottom to top, as raylab writes them)."""

import numpy as np


def write_pfm(path, img):
    """Standard little-endian colour PFM; img is (H, W, 3), row 0 = top."""
    img = np.ascontiguousarray(img, dtype=np.float32)
    h, w, c = img.shape
    assert c == 3
    with open(path, "wb") as f:
        f.write(b"PF\n%d %d\n-1.0\n" % (w, h))
        f.write(np.flipud(img).astype("<f4").tobytes())


def read_pfm(path):
    """A colour (PF) or grey (Pf) PFM as float32, (H, W, C), row 0 = top."""
    with open(path, "rb") as f:
        tag = f.readline().strip()
        w, h = map(int, f.readline().split())
        scale = float(f.readline())
        c = 3 if tag == b"PF" else 1
        dt = "<f4" if scale < 0 else ">f4"
        data = np.frombuffer(f.read(w * h * c * 4), dtype=dt)
    return np.flipud(data.reshape(h, w, c)).astype(np.float32)
