"""The 200-clients drill: many API clients at once against the production server.

Starts Gunicorn + Uvicorn workers (README's production section) on a fresh
database, then every client posts a note and a mode report, ROUNDS times, all
starting together. Prints the answers by status, refusals (each must be a 503
with Retry-After), latencies, and what the database kept: every 201 note
stored exactly once, one open master.

    .venv/bin/python benchmarks/api_concurrency.py --database spatialite
    .venv/bin/python benchmarks/api_concurrency.py --database postgis \\
        --postgres postgresql://ftt:ftt@127.0.0.1:5432/postgres
"""

import argparse
import statistics
import sys
import tempfile
import uuid
from collections import Counter
from pathlib import Path

import psycopg

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from tests.support.drill import WebServer, prepare, run_drill, stored  # noqa: E402


def fresh_postgis(admin_url: str) -> tuple[str, str]:
    name = f"ftt_drill_{uuid.uuid4().hex[:8]}"
    with psycopg.connect(admin_url, autocommit=True) as conn:
        conn.execute(f'CREATE DATABASE "{name}"')
    with psycopg.connect(admin_url.rsplit("/", 1)[0] + f"/{name}", autocommit=True) as conn:
        conn.execute("CREATE EXTENSION IF NOT EXISTS postgis")
    return name, admin_url.rsplit("/", 1)[0].replace("postgresql://", "postgis://") + f"/{name}"


def drop_postgis(admin_url: str, name: str):
    with psycopg.connect(admin_url, autocommit=True) as conn:
        conn.execute(f'DROP DATABASE IF EXISTS "{name}" WITH (FORCE)')


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--database", choices=["spatialite", "postgis"], default="spatialite")
    parser.add_argument("--postgres", default="postgresql://ftt:ftt@127.0.0.1:5432/postgres")
    parser.add_argument("--clients", type=int, default=200)
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--workers", type=int, default=2, help="web processes")
    args = parser.parse_args()

    with tempfile.TemporaryDirectory() as data_dir:
        env = {"FTT_DATA_DIR": data_dir}
        db_name = None
        if args.database == "postgis":
            db_name, env["FTT_DATABASE_URL"] = fresh_postgis(args.postgres)
        server = WebServer(env, workers=args.workers, log=Path(data_dir) / "server.log")
        try:
            server.start()
            setup = prepare(server)
            result = run_drill(server.url, setup, args.clients, args.rounds)
            kept = stored(server, setup, result["created_note_uids"])
        finally:
            server.stop()
            refusals = [
                line
                for line in (Path(data_dir) / "server.log").read_text().splitlines()
                if "refused while" in line
            ]
            if db_name:
                drop_postgis(args.postgres, db_name)

    lat = result["latencies"]
    print(
        f"database {args.database}, {args.workers} web processes, "
        f"{args.clients} clients x {args.rounds} rounds"
    )
    print(
        f"requests {result['requests']} in {result['seconds']:.1f} s "
        f"({result['requests'] / result['seconds']:.0f} req/s)"
    )
    print(f"answers by status {result['statuses']}")
    share = 100 * result["refused"] / result["requests"]
    print(
        f"refused {result['refused']} ({share:.2f} %), "
        f"without Retry-After {result['refused_without_retry_after']}"
    )
    for detail, count in result["refusal_details"].items():
        print(f"  {count} x {detail}")
    for cause, count in Counter(line.split(": ", 2)[-1] for line in refusals).items():
        print(f"  server log: {count} x {cause}")
    p95 = lat[int(0.95 * len(lat)) - 1]
    print(f"latency median {statistics.median(lat):.2f} s, p95 {p95:.2f} s, max {lat[-1]:.2f} s")
    print(
        f"notes answered 201: {len(result['created_note_uids'])}, stored with those uids: "
        f"{kept['posted_uids_stored']}, notes in the leg {kept['notes']} "
        f"(distinct uids {kept['distinct_note_uids']}), open masters {kept['open_masters']}"
    )


if __name__ == "__main__":
    main()
