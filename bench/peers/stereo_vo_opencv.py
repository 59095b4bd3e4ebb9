"""OpenCV's stereo visual odometry beside gpodo's, on the same rendered frames.

The folder comes from gpodo's example (rectified 512 x 384 pairs of the
stereo VO's accuracy test, the calibration, the truth, the prior and gpodo's
estimate per pair of frames):

    cargo run --release -p gpodo-experiments --example stereo_sequence -- /tmp/seq
    target/ci-python/bin/python bench/peers/stereo_vo_opencv.py /tmp/seq

OpenCV's pipeline, one thread (`cv2.setNumThreads(1)`), per pair:

* ORB (`cv2.ORB_create`) on both images with gpodo's ORB settings: the
  same feature cap, scale factor 1.2, levels and FAST threshold 20
  (OpenCV ranks corners by the Harris score and has no second threshold).
* Stereo: each left keypoint's best right keypoint by a brute-force
  Hamming matcher (`cv2.BFMatcher.knnMatch` with a mask) among those on
  its rows (within 2 scaled pixels) with a disparity in (0, f], accepted
  below distance 75 (ORB-SLAM2's stereo threshold), then refined to a
  sub-pixel disparity by `cv2.matchTemplate` (sum of squared differences,
  an 11 x 11 patch, 5 px each side) and a parabola through the best three.
* Map points: the reference's matched keypoints closer than 40 baselines.
* Tracking: each map point projected by the prior, matched by the same
  masked brute-force matcher to the current left keypoints within 7 px
  times its level's scale on a level next to its own, best distance at
  most 100 and below 0.9 of the second best; then
  `cv2.solvePnPRansac` (P3P, 200 iterations, 2.45 px, the square root of
  the 2-dof chi-square 5.991) and `cv2.solvePnPRefineLM` on its inliers;
  lost below 30 inliers.

The clock runs over the current pair's features, stereo matching and
tracking (the reference's features cached), as gpodo's `gpodo_secs`.
Errors are of the left camera's motion: `estimate^-1 * truth`, its
translation's norm and its rotation's angle. One JSON line per gap, then
a Markdown table.
"""

import argparse
import csv
import json
import pathlib
import statistics
import time

import cv2
import numpy as np


def quaternion_matrix(x, y, z, w):
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def pose(row, prefix):
    """A 4 x 4 pose from the row's `prefix_t*`, `prefix_q*` fields."""
    if row[f"{prefix}_tx"] == "":
        return None
    f = {k: float(row[f"{prefix}_{k}"]) for k in ("tx", "ty", "tz", "qx", "qy", "qz", "qw")}
    m = np.eye(4)
    m[:3, :3] = quaternion_matrix(f["qx"], f["qy"], f["qz"], f["qw"])
    m[:3, 3] = [f["tx"], f["ty"], f["tz"]]
    return m


def errors(estimate, truth):
    """Translation (m) and rotation (degrees) of `estimate^-1 * truth`."""
    d = np.linalg.inv(estimate) @ truth
    cos = np.clip((np.trace(d[:3, :3]) - 1) / 2, -1, 1)
    return float(np.linalg.norm(d[:3, 3])), float(np.degrees(np.arccos(cos)))


class Vo:
    def __init__(self, folder, cal):
        self.folder = folder
        self.cal = cal
        orb = cal["orb"]
        self.orb = cv2.ORB_create(
            nfeatures=orb["features"],
            scaleFactor=orb["scale_factor"],
            nlevels=orb["levels"],
            edgeThreshold=19,
            patchSize=31,
            fastThreshold=orb["ini_threshold"],
        )
        self.scales = orb["scale_factor"] ** np.arange(orb["levels"])
        self.matcher = cv2.BFMatcher(cv2.NORM_HAMMING)
        self.f, self.cx, self.cy = cal["focal_px"], cal["cx"], cal["cy"]
        self.b = cal["baseline_m"]
        self.k = np.array([[self.f, 0, self.cx], [0, self.f, self.cy], [0, 0, 1.0]])
        self.cache = {}

    def images(self, k):
        read = lambda side: cv2.imread(str(self.folder / side / f"{k:06}.png"), cv2.IMREAD_GRAYSCALE)
        return read("left"), read("right")

    def features(self, left, right):
        kl, dl = self.orb.detectAndCompute(left, None)
        kr, dr = self.orb.detectAndCompute(right, None)
        pl = np.array([k.pt for k in kl]).reshape(-1, 2)
        pr = np.array([k.pt for k in kr]).reshape(-1, 2)
        ll = np.array([k.octave for k in kl], dtype=int)
        disparity = np.full(len(kl), np.nan)
        if len(kl) and len(kr):
            rows = np.abs(pl[:, None, 1] - pr[None, :, 1]) <= 2 * self.scales[ll][:, None]
            d = pl[:, None, 0] - pr[None, :, 0]
            mask = (rows & (d > 0) & (d <= self.f)).astype(np.uint8)
            for m in self.matcher.knnMatch(dl, dr, k=1, mask=mask):
                if m and m[0].distance <= 75:
                    i, j = m[0].queryIdx, m[0].trainIdx
                    disparity[i] = self.refine(left, right, pl[i], pr[j, 0])
        return {"points": pl, "levels": ll, "descriptors": dl, "disparity": disparity}

    def refine(self, left, right, p, right_x):
        """Sub-pixel disparity: SSD of an 11 x 11 patch over +-5 px, parabola."""
        x, y, xr = int(round(p[0])), int(round(p[1])), int(round(right_x))
        w, h = left.shape[1], left.shape[0]
        if not (5 <= y < h - 5 and 5 <= x < w - 5 and 10 <= xr < w - 10):
            return np.nan
        patch = left[y - 5 : y + 6, x - 5 : x + 6]
        strip = right[y - 5 : y + 6, xr - 10 : xr + 11]
        ssd = cv2.matchTemplate(strip, patch, cv2.TM_SQDIFF).ravel()
        i = int(np.argmin(ssd))
        if i in (0, len(ssd) - 1):
            return np.nan
        a, c, e = ssd[i - 1], ssd[i], ssd[i + 1]
        denom = a - 2 * c + e
        delta = 0.0 if denom <= 0 else 0.5 * (a - e) / denom
        if abs(delta) > 1:
            return np.nan
        best_right = xr - 5 + i + delta
        d = x - best_right
        return d if d > 0 else np.nan

    def frame(self, k):
        if k not in self.cache:
            self.cache[k] = self.features(*self.images(k))
        return self.cache[k]

    def track(self, reference, current, prior):
        """`reference_from_current` (4 x 4) or None when lost."""
        valid = ~np.isnan(reference["disparity"])
        z = self.f * self.b / reference["disparity"][valid]
        keep = z <= 40 * self.b
        idx = np.flatnonzero(valid)[keep]
        z = z[keep]
        uv = reference["points"][idx]
        points = np.column_stack(((uv[:, 0] - self.cx) * z / self.f, (uv[:, 1] - self.cy) * z / self.f, z))
        camera_from_reference = np.linalg.inv(prior)
        x = points @ camera_from_reference[:3, :3].T + camera_from_reference[:3, 3]
        front = x[:, 2] > 0
        centre = np.column_stack((self.f * x[:, 0] / x[:, 2] + self.cx, self.f * x[:, 1] / x[:, 2] + self.cy))
        levels = reference["levels"][idx]
        radius = 7 * self.scales[levels]
        cp, cl = current["points"], current["levels"]
        near = np.linalg.norm(centre[:, None, :] - cp[None, :, :], axis=2) <= radius[:, None]
        mask = (near & (np.abs(levels[:, None] - cl[None, :]) <= 1) & front[:, None]).astype(np.uint8)
        obj, img = [], []
        for m in self.matcher.knnMatch(reference["descriptors"][idx], current["descriptors"], k=2, mask=mask):
            if not m or m[0].distance > 100:
                continue
            if len(m) == 2 and not m[0].distance < 0.9 * m[1].distance:
                continue
            obj.append(points[m[0].queryIdx])
            img.append(cp[m[0].trainIdx])
        if len(obj) < 30:
            return None
        obj, img = np.array(obj), np.array(img)
        ok, rvec, tvec, inliers = cv2.solvePnPRansac(
            obj, img, self.k, None, iterationsCount=200, reprojectionError=float(np.sqrt(5.991)),
            confidence=0.99, flags=cv2.SOLVEPNP_P3P,
        )
        if not ok or inliers is None or len(inliers) < 30:
            return None
        inliers = inliers.ravel()
        self.last_counts = (len(inliers), len(points))
        rvec, tvec = cv2.solvePnPRefineLM(obj[inliers], img[inliers], self.k, None, rvec, tvec)
        m = np.eye(4)
        m[:3, :3] = cv2.Rodrigues(rvec)[0]
        m[:3, 3] = tvec.ravel()
        return np.linalg.inv(m)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", type=pathlib.Path)
    args = parser.parse_args()
    cv2.setNumThreads(1)
    cal = json.loads((args.folder / "calibration.json").read_text())
    with open(args.folder / "pairs.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    vo = Vo(args.folder, cal)
    results = {}
    for row in rows:
        gap, first = int(row["gap"]), int(row["first"])
        truth, prior = pose(row, "truth"), pose(row, "prior")
        reference = vo.frame(first)
        left, right = vo.images(first + gap)
        started = time.perf_counter()
        current = vo.features(left, right)
        estimate = vo.track(reference, current, prior)
        secs = time.perf_counter() - started
        r = results.setdefault(gap, {"pairs": 0, "opencv": [], "gpodo": [], "opencv_secs": [], "gpodo_secs": [], "d": []})
        r["pairs"] += 1
        r["opencv_secs"].append(secs)
        r["gpodo_secs"].append(float(row["gpodo_secs"]))
        r["d"].append(float(np.linalg.norm(truth[:3, 3])))
        if estimate is not None:
            r["opencv"].append(errors(estimate, truth))
            r.setdefault("opencv_inliers", []).append(vo.last_counts[0])
            r.setdefault("opencv_map_points", []).append(vo.last_counts[1])
        if row["gpodo_inliers"] != "0":
            r.setdefault("gpodo_inliers", []).append(float(row["gpodo_inliers"]))
            r.setdefault("gpodo_map_points", []).append(float(row["gpodo_map_points"]))
        gpodo = pose(row, "gpodo")
        if gpodo is not None:
            r["gpodo"].append(errors(gpodo, truth))
    med = statistics.median
    table = []
    for gap, r in sorted(results.items()):
        line = {
            "gap_s": gap / cal["fps"],
            "pairs": r["pairs"],
            "displacement_mm": 1e3 * med(r["d"]),
            "opencv_version": cv2.__version__,
        }
        for who in ("gpodo", "opencv"):
            e = r[who]
            line[f"{who}_tracked"] = len(e)
            line[f"{who}_translation_mm"] = 1e3 * med([t for t, _ in e]) if e else None
            line[f"{who}_rotation_deg"] = med([a for _, a in e]) if e else None
            line[f"{who}_ms_per_frame"] = 1e3 * med(r[f"{who}_secs"])
            line[f"{who}_inliers"] = med(r.get(f"{who}_inliers", [0]))
            line[f"{who}_map_points"] = med(r.get(f"{who}_map_points", [0]))
        print(json.dumps(line))
        table.append(line)
    print()
    print("| gap | pairs | displacement | gpodo tracked | gpodo translation | gpodo rotation | OpenCV tracked | OpenCV translation | OpenCV rotation |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for t in table:
        print(
            f"| {t['gap_s']:.1f} s | {t['pairs']} | {t['displacement_mm']:.1f} mm | {t['gpodo_tracked']} "
            f"| {t['gpodo_translation_mm']:.2f} mm | {t['gpodo_rotation_deg']:.3f}° | {t['opencv_tracked']} "
            f"| {t['opencv_translation_mm']:.2f} mm | {t['opencv_rotation_deg']:.3f}° |"
        )
    print()
    print(
        "median inliers / map points: "
        + ", ".join(f"gap {t['gap_s']:.1f} s: gpodo {t['gpodo_inliers']:.0f} / {t['gpodo_map_points']:.0f}, OpenCV {t['opencv_inliers']:.0f} / {t['opencv_map_points']:.0f}" for t in table)
    )
    print(
        "time per processed stereo frame (median, one thread): "
        + ", ".join(f"gap {t['gap_s']:.1f} s: gpodo {t['gpodo_ms_per_frame']:.1f} ms, OpenCV {t['opencv_ms_per_frame']:.1f} ms" for t in table)
    )


if __name__ == "__main__":
    main()
