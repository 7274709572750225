"""Run ecattool commands in this process under an address-space limit, one after the other; write what each did.

``python -m tests.safe.bounded_child LIMIT_BYTES CASES.json RESULT.json``: CASES is a list of ``{"argv": [...],
"stdin": PATH or null}``; RESULT gets ``[{"code": int, "stdout": str, "stderr": str, "exception": str|null}]``.
Used by tests/safe/test_bounded_inputs.py (issue 28.2/28.5): every reader on an alias bomb, /dev/zero and a FIFO that
never ends must stop with one located line, in bounded memory. A MemoryError or any exception other than the
command's own exit is recorded as ``exception`` (the test fails on it).
"""

from __future__ import annotations

import io
import json
import resource
import sys


def main() -> int:
    limit, cases_path, result_path = int(sys.argv[1]), sys.argv[2], sys.argv[3]
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    from ecattool.cli import main as cli_main

    with open(cases_path, encoding="utf-8") as fh:
        cases = json.load(fh)
    results = []
    real = sys.stdin, sys.stdout, sys.stderr
    for case in cases:
        out, err = io.BytesIO(), io.BytesIO()
        tout = io.TextIOWrapper(out, encoding="utf-8", write_through=True)
        terr = io.TextIOWrapper(err, encoding="utf-8", write_through=True)
        sys.stdout, sys.stderr = tout, terr
        stdin = open(case["stdin"], "rb") if case.get("stdin") else None  # noqa: SIM115 - closed below
        if stdin is not None:
            sys.stdin = io.TextIOWrapper(stdin, encoding="utf-8")
        code, exception = 0, None
        try:
            cli_main(list(case["argv"]))
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else 0
        except BaseException as exc:  # noqa: BLE001 - recorded: the test fails on it
            code, exception = -1, f"{type(exc).__name__}: {exc}"[:500]
        finally:
            sys.stdin, sys.stdout, sys.stderr = real
            if stdin is not None:
                stdin.close()
        tout.flush()
        terr.flush()
        results.append({"code": code, "stdout": out.getvalue().decode("utf-8", "replace")[-2000:],
                        "stderr": err.getvalue().decode("utf-8", "replace")[-2000:], "exception": exception})
        tout.detach()
        terr.detach()
    with open(result_path, "w", encoding="utf-8") as fh:
        json.dump(results, fh)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
