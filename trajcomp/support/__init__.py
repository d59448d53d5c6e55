"""Plumbing every wing shares: nothing here knows about arms or programs.

`atomic` (files and file sets written whole or not at all), `memory`
(memory budgets), `parallel` (process pools over blocks), `threads` (one
BLAS / OpenMP thread per process), `progress` (progress bars), `signals`
(the signals that stop a run), `yaml_text` (safe YAML), `plain_data`
(numpy values as plain data) and `crash` (unexpected exceptions reported
as bugs).
"""
