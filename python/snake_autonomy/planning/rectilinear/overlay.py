"""The planner's view drawn on the head camera's image: the part perception found not traversable
tinted red, the candidate arcs projected (chosen: green, free parts of the others: yellow, blocked
parts: red). The planner node publishes it (nav/traversability); nav runs keep it per replan."""
import numpy as np


def overlay(rgb: np.ndarray, ground: np.ndarray, selection, checker) -> np.ndarray:
    """The camera image with the non-traversable part tinted red and the arcs drawn (chosen: green,
    free parts of the others: yellow, blocked parts: red)."""
    import cv2  # lazy: OpenCV is heavy and only this path needs it
    img = rgb.copy()
    img[~ground] = (0.5 * img[~ground] + [127, 0, 0]).astype(np.uint8)
    for i, a in enumerate(selection.arcs):
        pts = a.poses[:, :2]
        flat = np.column_stack([pts, np.zeros(len(pts))])
        z = flat @ checker._R[2] + checker._t[2]
        uv, _ = cv2.projectPoints(flat, checker.rvec, checker.tvec, checker.K, checker.dist)
        uv = uv.reshape(-1, 2)
        for j in range(len(uv) - 1):
            if z[j] <= 0.01 or z[j + 1] <= 0.01:
                continue
            free = a.s_m[j + 1] <= a.free_m + 1e-9
            colour = (0, 255, 0) if i == selection.chosen and free else ((255, 255, 0) if free else (255, 0, 0))
            p0 = tuple(int(v) for v in np.clip(uv[j], -1e4, 1e4))
            p1 = tuple(int(v) for v in np.clip(uv[j + 1], -1e4, 1e4))
            cv2.line(img, p0, p1, colour, 2)
    return img
