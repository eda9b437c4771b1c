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


def main():
    with open(sys.argv[1]) as handle:
        specs = json.load(handle)
    for spec in specs:
        draw(spec)
        print("wrote", spec["png"])


if __name__ == "__main__":
    main()
