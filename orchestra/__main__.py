"""Allow ``python -m orchestra``."""
try:
    from orchestra.cli import main
except KeyboardInterrupt:  # Ctrl-C while still importing: a normal end, not a traceback
    raise SystemExit(130) from None

if __name__ == "__main__":
    main()
