#!/bin/bash
# Usage: status.sh [OUT]
# Which bands of the frame submit.sh queued are done, queued, running or
# failed (with the tail of their logs), and the merge's state; exits 1 when
# something failed. The same as submit.sh --status.
exec "$(dirname "${BASH_SOURCE[0]}")/submit.sh" --status "$@"
