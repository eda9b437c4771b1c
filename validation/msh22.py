"""Gmsh msh 2.2 (ASCII) writer shared by the validation cases' make_mesh.py scripts.

write_msh22(path, names, nodes, elements): names = [(dimension, tag, "name"), ...] (physical groups),
nodes = [(x, y, z), ...] (tags 1..n in order), elements = [(gmsh type, physical tag, (node tags...)), ...]
(type 1: 2-node line, 3: 4-node quadrilateral). Coordinates are written with 15 significant digits.
"""


def write_msh22(path, names, nodes, elements):
    with open(path, "w") as f:
        f.write("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n")
        f.write(f"$PhysicalNames\n{len(names)}\n")
        for dim, tag, name in names:
            f.write(f'{dim} {tag} "{name}"\n')
        f.write("$EndPhysicalNames\n")
        f.write(f"$Nodes\n{len(nodes)}\n")
        for k, (x, y, z) in enumerate(nodes, 1):
            f.write(f"{k} {x:.15g} {y:.15g} {z:.15g}\n")
        f.write(f"$EndNodes\n$Elements\n{len(elements)}\n")
        for k, (etype, phys, conn) in enumerate(elements, 1):
            f.write(f"{k} {etype} 2 {phys} {phys} " + " ".join(map(str, conn)) + "\n")
        f.write("$EndElements\n")
