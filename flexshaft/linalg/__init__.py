"""Linear algebra: the sparse assembler, solvers chosen by size, eigensolvers, the one MAC, the one damped
eigen-solver, damping matrices."""
