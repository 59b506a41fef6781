# Two commands do everything on a fresh Debian bookworm machine:
#   make demo   set up, build, run the demo and print its report
#   make test   set up, build, run every gtest, pytest and rostest; fails if any test fails
# `make bench` runs the benchmarks. The catkin workspace lives outside the checkout (WS, default
# ~/.cache/mbot_slam_navigation_ws) around a link to it: a workspace inside the package would be
# searched by rosrun and give every executable twice.
SHELL := /bin/bash
.SHELLFLAGS := -eo pipefail -c
# ROS runs on Debian's /usr/bin/python3; another python3 may come first on PATH.
export PATH := /usr/bin:/bin:$(PATH)
WS ?= $(HOME)/.cache/mbot_slam_navigation_ws
export ROS_HOME ?= $(WS)/ros_home
export PYTHONDONTWRITEBYTECODE := 1
PKG := mbot_slam_navigation
JOBS ?= 2
SOURCE := source $(WS)/devel/setup.bash

.PHONY: setup build test demo bench clean print-ws

setup:
	@tools/setup_deps.sh
	@mkdir -p $(WS)/src $(ROS_HOME)
	@[ "$$(readlink $(WS)/src/$(PKG))" = "$(CURDIR)" ] || ln -sfn $(CURDIR) $(WS)/src/$(PKG)

build: setup
	cd $(WS) && catkin_make -j$(JOBS) -DCMAKE_BUILD_TYPE=Release -DPYTHON_EXECUTABLE=/usr/bin/python3 > $(WS)/build.log 2>&1 \
	  || { tail -n 60 $(WS)/build.log; echo "build failed: full log in $(WS)/build.log"; exit 1; }
	@echo "build: ok (log in $(WS)/build.log)"

test: build
	cd $(WS) && catkin_make -j$(JOBS) tests > $(WS)/build-tests.log 2>&1 \
	  || { tail -n 60 $(WS)/build-tests.log; echo "test build failed: $(WS)/build-tests.log"; exit 1; }
	cd $(WS) && $(SOURCE) && catkin_make -j1 run_tests 2>&1 | tee $(WS)/run-tests.log | grep -E '^\[ *(ROSTEST|OK|FAIL|RUN|PASSED)|^(FAILURE|ERROR|SUMMARY)|passed|failed' || true
	cd $(WS) && catkin_test_results --verbose build/test_results

# The exploration as fast as the stack keeps up on this machine (real_time_factor auto), ended by
# run_exploration with one line giving the outcome; exits 0 only for outcome complete. RVIZ=1 also
# opens rviz.
RVIZ ?= 0
# ROBOTS=2 (up to 4): a team explores together (launch/multi_explore.launch), one report for all.
# HOSTS=separate: each robot on a host of its own and a base station (network namespaces of this
# machine, tools/multi_host.py; needs root).
HOSTS ?= one
demo: build
ifeq ($(HOSTS),separate)
	cd $(WS) && $(SOURCE) && /usr/bin/python3 $(CURDIR)/tools/multi_host.py --robots $(or $(ROBOTS),2) \
	  --report-dir $(CURDIR)/report --max-duration 1200 --launch-arg rviz:=$(if $(filter 1 true,$(RVIZ)),true,false)
else
	cd $(WS) && $(SOURCE) && rosrun $(PKG) run_exploration $(PKG) \
	  $(if $(filter-out 1,$(or $(ROBOTS),1)),multi_explore.launch robots:=$(ROBOTS),explore.launch) \
	  report_dir:=$(CURDIR)/report real_time_factor:=auto max_duration:=1200 rviz:=$(if $(filter 1 true,$(RVIZ)),true,false)
endif

bench: build
	cd $(WS) && $(SOURCE) && /usr/bin/python3 $(CURDIR)/bench/run_all.py

clean:
	rm -rf $(WS)/build $(WS)/devel

print-ws:
	@echo $(WS)
