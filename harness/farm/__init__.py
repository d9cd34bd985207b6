"""The farm: CASSI-agnostic batch execution. It knows jobs and bytes, not faces.

- :mod:`.jobs` -- the job model (batch -> job -> frame) and a job's execution in a worker;
- :mod:`.plan` -- which jobs a run has and what each waits for, as plain data;
- :mod:`.runner` -- the scheduler: skip what is done, run the rest, write the tables;
- :mod:`.store` -- content-addressed, atomically written outputs, the run lock, resume checks;
- :mod:`.executors` -- local worker processes or a Ray cluster; :mod:`.workers` -- a worker's
  thread environment;
- :mod:`.results` -- the long results table; :mod:`.tableset` -- a run's tables as one set;
- :mod:`.progress` -- progress bars, job logs and the run's summary.
"""
