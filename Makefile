# Two commands on a fresh Debian bookworm machine (as root):  make demo   and   make test
# Both provision first: Debian's ROS 1 packages, the .venv with pinned PyPI packages, and the catkin
# workspace in .ws/ -- each only if missing, so a second run installs nothing.
SHELL := /bin/bash
IN_ENV := source ./env.sh &&

.PHONY: provision demo test unit rostest bench screenshot compat fresh clean

provision:
	@bash tools/provision.sh

demo: provision
	@$(IN_ENV) python3 tools/demo.py $(DEMO_ARGS)

test: provision
	@$(IN_ENV) python3 tools/run_tests.py $(TEST_ARGS)

unit: provision
	@$(IN_ENV) python3 tools/run_tests.py --unit-only

bench: provision
	@$(IN_ENV) python3 tools/bench.py $(BENCH_ARGS)

screenshot: provision
	@$(IN_ENV) python3 tools/screenshot.py $(SCREENSHOT_ARGS)

# The ROS-free unit tests under Python 3.8 (ROS Noetic's), where a python3.8 exists (PATH or pyenv).
compat:
	@bash tools/compat.sh

# The two commands above on a bare Debian bookworm made with debootstrap, in a clean environment (tools/fresh.py;
# as root; about 20 minutes). Run it before resolving an issue that touches provisioning, tests or dependencies.
fresh:
	@/usr/bin/python3 tools/fresh.py $(FRESH_ARGS)

clean:
	rm -rf .ws .venv38 test_output
