"""The few OBJ records the validators read, parsed by hand (shares no code with lamina)."""


def read_obj(path, record):
    """Vertex positions and the 0-based vertex indices of every `record` line ("f" or "l")."""
    verts, records = [], []
    with open(path) as f:
        for raw in f:
            w = raw.split()
            if not w:
                continue
            if w[0] == "v":
                verts.append(tuple(float(x) for x in w[1:4]))
            elif w[0] == record:
                records.append([int(t.split("/")[0]) - 1 for t in w[1:]])
    return verts, records
