"""The attacks on the graders (docs/grading-security.md), one module per kind."""
