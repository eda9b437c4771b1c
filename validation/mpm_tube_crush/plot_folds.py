"""Fold shapes of the tube crush at 5, 10 and 15 ms (the instants of the seed's LS-DYNA comparison).

Usage: /usr/bin/python3 plot_folds.py RESULT_DIR [OUT.png]
RESULT_DIR is a lamina result folder of this case (frame_*.vtu every 0.5 ms, as case.yaml writes them:
`lamina run validation/mpm_tube_crush/case.yaml -o out/crush`, or the run folder `lamina validate`
writes). Draws the wall section in the plane x = 0 (the two faces y = +-30) and the 3D shape coloured
by the equivalent plastic strain.
"""
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import vtk
from vtk.util.numpy_support import vtk_to_numpy

FRAMES = {5.0: 10, 10.0: 20, 15.0: 30}  # time (ms) -> frame index (output every 0.5 ms)


def read(path):
    reader = vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(path)
    reader.Update()
    grid = reader.GetOutput()
    points = vtk_to_numpy(grid.GetPoints().GetData())
    displacement = vtk_to_numpy(grid.GetPointData().GetArray("displacement"))
    plastic = vtk_to_numpy(grid.GetPointData().GetArray("plastic_strain"))
    return points, points - displacement, plastic


def main():
    folder = sys.argv[1]
    out = sys.argv[2] if len(sys.argv) > 2 else "tube_crush_folds.png"
    figure = plt.figure(figsize=(12, 7.5), dpi=100)
    for column, (time, frame) in enumerate(FRAMES.items()):
        x, reference, plastic = read(f"{folder}/frame_{frame:05d}.vtu")
        section = figure.add_subplot(2, 3, column + 1)
        for side in (1, -1):  # the faces y = +30 and y = -30, ordered along the tube
            keep = (np.abs(reference[:, 0]) < 1e-6 * 60 + 1.0) & (side * reference[:, 1] > 0)
            order = np.argsort(reference[keep, 2])
            section.plot(x[keep, 1][order], x[keep, 2][order], "-", color="tab:blue", linewidth=1.2)
        section.set_aspect("equal")
        section.set_xlim(-60, 60)
        section.set_ylim(-5, 305)
        section.set_title(f"t = {time:g} ms: section x = 0", fontsize=9)
        section.set_xlabel("y (mm)")
        section.set_ylabel("z (mm)")
        view = figure.add_subplot(2, 3, column + 4, projection="3d")
        shown = view.scatter(x[:, 0], x[:, 1], x[:, 2], c=plastic, s=1.5, cmap="viridis", vmin=0, vmax=0.5)
        view.set_box_aspect((60, 60, 300))
        view.set_zlim(0, 300)
        view.set_title(f"t = {time:g} ms, plastic strain", fontsize=9)
        view.set_axis_off()
    figure.colorbar(shown, ax=figure.axes, shrink=0.4, label="equivalent plastic strain (clipped at 0.5)")
    figure.suptitle("Square tube crush, 500 kg at 15 mm/ms (lamina mpm, 48 x 60 BT shell domains)", fontsize=10)
    figure.savefig(out)
    print(out)


if __name__ == "__main__":
    main()
