"""The units of time rpbench converts between (lengths are metres and speeds metres per second throughout)."""

MINUTE_S = 60.0
HOUR_S = 3600.0
DAY_S = 86400.0
