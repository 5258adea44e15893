"""synth: task-level synthesis of AL manipulator programs, after R. H. Taylor (1976).

Data flow (see ``docs/design.md``): task YAML → :mod:`synth.models` → :mod:`synth.errors` →
:mod:`synth.strategies` → :mod:`synth.codegen` → :mod:`synth.al` / :mod:`synth.replay`.
"""

__version__ = "0.1.0"
