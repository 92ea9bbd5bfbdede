# The swim workspace. Every target runs the one setup step first (scripts/setup.sh: idempotent).
.PHONY: setup demo test bench clean

setup:
	@bash scripts/setup.sh

demo: setup
	@bash scripts/run_in_env.sh ros2 run swim_bringup swim-demo

test: setup
	@bash scripts/run_tests.sh

bench: setup
	@bash scripts/run_in_env.sh bash -c 'for b in bench/*.py; do python "$$b"; done'

clean:
	rm -rf build install log
