# Soak test and latency tool: filled in by the load-test work.
