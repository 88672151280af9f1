"""The legsim bench, in wings: scene.py and recording.py (the scene a run is made of, the file a
run leaves), hil/ (running scenes), verdict/ (checking recordings), reference/ (the independent
models), report/ (tables and plots), benchmarks/ (measurements of the core and its peers)."""
