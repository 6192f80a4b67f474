"""The built-in model files: the study's three test-bench set-ups (Customer 1, Customer 2, Without DUT).

They ship with the package so that ``flexshaft demo`` works from any install;
``examples/customer1.toml`` and its siblings are links to these files, not copies.
"""
