"""The jobs: a program's whole route (read, compensate, re-time, write, report) and batches of them.

Above the stages (`trajcomp.compensation`, `trajcomp.timing`,
`trajcomp.report`), below the faces that run them: the CLI's commands, the
Python API and the plugins.

- `trajcomp.jobs.pipeline`: `CompensationJob` (compensate, or convert, one
  program) and `RetimeJob` (re-time one program, no model);
- `trajcomp.jobs.batch`: many programs through one job, in parallel, with a
  summary.
"""
