"""Independent reference implementations that the tests and the benchmarks compare
the production code against (plain filterpy filters, per-sample loops, numpy
versions of compiled code). Not used by the environments."""
