"""The package's benchmarks: run each as ``python -m benchmarks.NAME`` from the repository
root (``--help`` for its options). They use the package's public API only."""
