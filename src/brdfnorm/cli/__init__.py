def main() -> None:
    raise SystemExit("brdfnorm CLI not built yet")
