# The two commands: `make demo` and `make test`. Both install what is missing (Debian packages,
# the clone's .venv), build with catkin in .ws/, and are quiet when everything is there.
SHELL := /bin/bash
.DEFAULT_GOAL := help
WITH_ENV := scripts/with-env

.PHONY: help deps build test demo bench clean

help:
	@echo "make demo   install, build, run the simulated robot through its main mission, write results/"
	@echo "make test   install, build, run every test (gtest, layers, style, pytest, rostest); ends with 'N passed, N failed'"
	@echo "make build  install and build only"
	@echo "make bench  run the benchmarks in bench/ and print their figures"

deps:
	@scripts/bootstrap

build: deps
	@scripts/build

test: build
	@$(WITH_ENV) python3 scripts/run_tests

demo: build
	@$(WITH_ENV) python3 scripts/demo

bench: build
	@$(WITH_ENV) bash bench/run_all

clean:
	rm -rf .ws test_results
