#!/usr/bin/python3
"""Draw the validation plots that `lamina validate` asks for (plots.json): for every plot, the
reference data as markers and lamina's result as a line, with labelled axes. Uses Debian's
python3-matplotlib (Agg backend, no display needed)."""
import csv
import json
import sys
import textwrap

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read_csv(path):
    """Columns of a CSV file with a header row; '#' lines are comments."""
    with open(path, newline="") as handle:
        lines = [line for line in handle if line.strip() and not line.lstrip().startswith("#")]
    rows = list(csv.reader(lines))
    header = [h.strip() for h in rows[0]]
    columns = {name: [] for name in header}
    for row in rows[1:]:
        for name, cell in zip(header, row):
            try:
                columns[name].append(float(cell))
            except ValueError:
                columns[name].append(cell.strip())
    return columns


def select_rows(columns, wanted):
    """Keep the rows whose cells equal the wanted values (text comparison)."""
    if not columns or not wanted:
        return columns
    count = len(next(iter(columns.values())))
    keep = [i for i in range(count)
            if all(str(columns.get(key, [""] * count)[i]) == value or
                   (isinstance(columns.get(key, [None] * count)[i], float) and value.replace(".", "", 1).isdigit()
                    and float(value) == columns[key][i]) for key, value in wanted.items())]
    return {name: [values[i] for i in keep] for name, values in columns.items()}


def draw(spec):
    lamina = read_csv(spec["lamina_csv"])
    reference = read_csv(spec["reference_csv"]) if spec.get("reference_csv") else {}
    reference = select_rows(reference, spec.get("reference_row", {}))
    figure, axes = plt.subplots(figsize=(6.4, 4.4), dpi=120)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    x = lamina[spec["x"]]
    for index, name in enumerate(spec["y"]):
        colour = colours[index % len(colours)]
        values = lamina[name]
        if spec.get("relative_error_to") is not None:  # convergence plot: |y / exact - 1|
            exact = spec["relative_error_to"]
            values = [abs(v / exact - 1.0) for v in values]
        pairs = sorted(zip(x, values))
        if spec.get("relative_error_to") is not None:
            axes.plot([p[0] for p in pairs], [p[1] for p in pairs], "-s", color=colour, markersize=4,
                      label=f"lamina |{name} / {spec['relative_error_to']:g} - 1|")
        else:
            axes.plot([p[0] for p in pairs], [p[1] for p in pairs], "-", color=colour, label=f"lamina {name}")
        if index < len(spec.get("reference_y", [])) and reference and spec.get("relative_error_to") is None:
            ref_name = spec["reference_y"][index]
            ref_x = reference.get(spec.get("reference_x") or spec["x"], [])
            ref_y = reference.get(ref_name, [])
            points = [(a, b) for a, b in zip(ref_x, ref_y) if isinstance(a, float) and isinstance(b, float)]
            if points:
                axes.plot([p[0] for p in points], [p[1] for p in points], "o", color=colour, markersize=8,
                          markerfacecolor="none", markeredgewidth=1.8, label=f"reference {ref_name}")
    if spec.get("log_x"):
        axes.set_xscale("log")
    if spec.get("log_y"):
        axes.set_yscale("log")
    axes.set_xlabel(spec.get("xlabel") or spec["x"])
    axes.set_ylabel(spec.get("ylabel") or ", ".join(spec["y"]))
    title = spec.get("title", "")
    if spec.get("reference_label"):
        title += "\n" + textwrap.shorten("reference: " + spec["reference_label"], width=80, placeholder=" ...")
    axes.set_title(title, fontsize=9)
    axes.grid(True, which="both", alpha=0.3)
    axes.legend(fontsize=8)
    figure.tight_layout()
    figure.savefig(spec["png"])
    plt.close(figure)


def read_vtu(path, field):
    """Points and one point-data array of a lamina VTU file (inline base64 binary, UInt32 byte count), or
    of a .pvtu frame of a run on several ranks (its pieces in order)."""
    import base64
    import os
    import re
    import struct

    import numpy as np

    text = open(path).read()
    if path.endswith(".pvtu"):
        pieces = [read_vtu(os.path.join(os.path.dirname(path), source), field)
                  for source in re.findall(r'<Piece Source="([^"]+)"', text)]
        if not pieces:
            raise ValueError(f"{path}: no pieces")
        return np.vstack([p for p, _ in pieces]), np.vstack([v for _, v in pieces])

    def decode(block):
        raw = base64.b64decode(block.strip())
        count = struct.unpack("<I", raw[:4])[0]
        return np.frombuffer(raw[4:4 + count], dtype="<f8")

    points = re.search(r"<Points>\s*<DataArray[^>]*>\s*([^<]+)</DataArray>", text)
    values = re.search(r'<DataArray type="Float64" Name="' + re.escape(field) +
                       r'"(?: NumberOfComponents="(\d+)")?[^>]*>\s*([^<]+)</DataArray>', text)
    if not points or not values:
        raise ValueError(f"{path}: no points or no point data '{field}'")
    components = int(values.group(1) or 1)
    return decode(points.group(1)).reshape(-1, 3), decode(values.group(2)).reshape(-1, components)


def draw_snapshots(spec):
    """One contour panel per requested time / load factor: the nearest frame of the run's result.pvd,
    the field component over the in-plane reference coordinates (averaged through the thickness)."""
    import os
    import re

    import numpy as np

    directory = spec["run_directory"]
    pvd = open(os.path.join(directory, "result.pvd")).read()
    frames = [(float(t), f) for t, f in re.findall(r'timestep="([^"]+)"[^>]*file="([^"]+)"', pvd)]
    if not frames:
        raise ValueError(f"{directory}/result.pvd lists no frames")
    chosen = []
    for wanted in spec["at"]:
        chosen.append(min(frames, key=lambda frame: abs(frame[0] - wanted)))
    figure, axes = plt.subplots(1, len(chosen), figsize=(3.2 * len(chosen), 3.0), dpi=120, squeeze=False)
    for panel, (time, name) in zip(axes[0], chosen):
        points, values = read_vtu(os.path.join(directory, name), spec["field"])
        component = values[:, min(spec.get("component", 0), values.shape[1] - 1)]
        key = np.round(points[:, :2], 6)
        unique, inverse = np.unique(key, axis=0, return_inverse=True)
        inverse = inverse.reshape(-1)
        mean = np.bincount(inverse, weights=component) / np.bincount(inverse)
        contour = panel.tricontourf(unique[:, 0], unique[:, 1], mean, levels=21, cmap="RdBu_r")
        panel.set_aspect("equal")
        panel.set_title(f"at {time:.4g}: max |{spec['field']}_{'xyz'[spec.get('component', 0)]}| {np.abs(mean).max():.3g}",
                        fontsize=8)
        panel.tick_params(labelsize=7)
        figure.colorbar(contour, ax=panel, shrink=0.8).ax.tick_params(labelsize=7)
    figure.suptitle(spec.get("title", ""), fontsize=9)
    figure.tight_layout()
    figure.savefig(spec["png"])
    plt.close(figure)


def main():
    with open(sys.argv[1]) as handle:
        specs = json.load(handle)
    for spec in specs:
        if spec.get("kind") == "snapshots":
            draw_snapshots(spec)
        else:
            draw(spec)
        print("wrote", spec["png"])


if __name__ == "__main__":
    main()
