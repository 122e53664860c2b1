"""The work of each ``planner`` command, one function per command taking the parsed
arguments (:class:`argparse.Namespace`) and returning the exit status; the parser is in
:mod:`planner.cli`."""
