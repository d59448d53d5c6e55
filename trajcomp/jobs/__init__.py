"""The jobs: a program's whole route (read, compensate, re-time, write, report) and batches of them.

Above the stages (`trajcomp.compensation`, `trajcomp.timing`,
`trajcomp.report`), below the faces that run them: the CLI's commands, the
Python API, the plugins and the demo (`trajcomp.paper_protocol`). No face
writes a program file itself (tests/test_layout.py).

- `trajcomp.jobs.pipeline`: `CompensationJob` (compensate one program, and
  write it in its own language or another);
- `trajcomp.jobs.retime`: `RetimeJob` (re-time one program, no model);
- `trajcomp.jobs.convert`: `ConvertJob` (rewrite one program in another
  language, no model);
- `trajcomp.jobs.batch`: many programs through one job, in parallel, with a
  summary;
- `trajcomp.jobs.options`: the jobs' options, checked in one place;
- `trajcomp.jobs.program_run`: what a job did with one file (`ProgramRun`).
"""
