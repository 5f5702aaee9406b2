"""Connected pieces of a graph given as node count and edge pairs (shares no code with lamina)."""


def component_labels(n, edges):
    """For each node 0..n-1, the smallest node of its connected piece."""
    parent = list(range(n))

    def find(x):
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x

    for a, b in edges:
        ra, rb = find(a), find(b)
        if ra != rb:
            parent[max(ra, rb)] = min(ra, rb)
    return [find(v) for v in range(n)]


def component_count(n, edges):
    return len(set(component_labels(n, edges)))
