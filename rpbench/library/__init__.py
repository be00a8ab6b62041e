"""The citable instance library: named, versioned sets of frozen rpbench decision models that papers
can cite, each set pinned by a manifest of digests and known optima, and every model also written in
the file formats command-line solvers read (MPS, LP, DIMACS assignment, a weighted edge list).
"""
