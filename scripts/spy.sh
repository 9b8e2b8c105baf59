#!/usr/bin/env bash
# lcm-spy for peritwin: LCM's traffic inspector (lcm.spy.Spy) with the peritwin_msgs types, so
# every PERITWIN_* channel is decoded, and with jchart2d, which its message viewer and plots need.
# Debian's /usr/bin/lcm-spy does not run here: it passes -Xincgc (refused by Java >= 9), and its
# -cp hides $CLASSPATH, so it never sees peritwin_msgs.jar (issue 17).
set -euo pipefail

usage() {
  cat <<'EOF'
usage: scripts/spy.sh [--build-dir DIR] [--lcm-url URL | URL]
       scripts/spy.sh [--build-dir DIR] --classpath

Starts lcm-spy (lcm.spy.Spy) on the LCM URL with the peritwin message types: every PERITWIN_*
channel is listed with its type; double-click one for the message viewer, click a number there for
its plot. Needs an X display (under ssh: -X; without one: xvfb-run -a scripts/spy.sh URL).

  URL, --lcm-url URL  the bus, e.g. tcpq://127.0.0.1:7700 (a TCP hub) or
                      udpm://239.255.76.67:7667; default $LCM_DEFAULT_URL, then LCM's default
  --build-dir DIR     the build directory holding peritwin_msgs.jar
                      (default $PERITWIN_BUILD_DIR, then build/ in the repository)
  --classpath         print the Java class path and exit
  -h, --help          this text

Jars (exit 2 naming the package to install when one is missing):
  lcm.jar             liblcm-java          (in $PERITWIN_JAVA_DIR, default /usr/share/java)
  jchart2d.jar        libjchart2d-java     (same directory)
  peritwin_msgs.jar   the build: cmake --build build --target peritwin_messages_jar (needs a JDK)
Anything in $CLASSPATH (other type jars, Spy plugins) is appended to the class path.
EOF
}

repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build_dir=${PERITWIN_BUILD_DIR:-$repo/build}
java_dir=${PERITWIN_JAVA_DIR:-/usr/share/java}
url=${LCM_DEFAULT_URL:-}
print_classpath=0
url_given=0

die_usage() {
  echo "spy.sh: $1 (see --help)" >&2
  exit 2
}

while [ $# -gt 0 ]; do
  case "$1" in
    -h | --help) usage; exit 0 ;;
    --classpath) print_classpath=1 ;;
    --build-dir)
      [ $# -ge 2 ] || die_usage "--build-dir needs a directory"
      build_dir=$2; shift ;;
    --build-dir=*) build_dir=${1#--build-dir=} ;;
    -l | --lcm-url)
      [ $# -ge 2 ] || die_usage "$1 needs a URL"
      url=$2; url_given=$((url_given + 1)); shift ;;
    --lcm-url=*) url=${1#--lcm-url=}; url_given=$((url_given + 1)) ;;
    -*) die_usage "unknown option $1" ;;
    *) url=$1; url_given=$((url_given + 1)) ;;
  esac
  shift
done
[ "$url_given" -le 1 ] || die_usage "one LCM URL only"

missing=()
lcm_jar=$java_dir/lcm.jar
jchart_jar=$java_dir/jchart2d.jar
types_jar=$build_dir/peritwin_msgs.jar
[ -f "$lcm_jar" ] || missing+=("$lcm_jar: install the Debian package liblcm-java")
# jchart2d: Spy's message viewer (ObjectPanel) draws every number's sparkline with it, so without
# it double-clicking a channel throws NoClassDefFoundError: info/monitorenter/gui/chart/ITrace2D.
# Its own dependencies (jide-oss, xmlgraphics-commons) come through its manifest's Class-Path.
[ -f "$jchart_jar" ] || missing+=("$jchart_jar: install the Debian package libjchart2d-java")
[ -f "$types_jar" ] || missing+=("$types_jar: build it with 'cmake --build $build_dir --target peritwin_messages_jar' (needs a JDK: openjdk-17-jdk-headless), or name the build with --build-dir")
if ! java_bin=$(command -v java); then
  missing+=("java: install the Debian package default-jre")
elif java_home=$(dirname "$(dirname "$(readlink -f "$java_bin")")") &&
     [ -d "$java_home/lib" ] && ! [ -e "$java_home/lib/libawt_xawt.so" ]; then
  # A headless runtime (default-jre-headless alone) cannot open Spy's window.
  missing+=("$java_home/lib/libawt_xawt.so (the Java runtime is headless): install the Debian package default-jre")
fi
if [ ${#missing[@]} -gt 0 ]; then
  for m in "${missing[@]}"; do echo "spy.sh: missing $m" >&2; done
  echo "spy.sh: scripts/install-deps.sh installs the packages" >&2
  exit 2
fi

classpath=$lcm_jar:$types_jar:$jchart_jar${CLASSPATH:+:$CLASSPATH}
if [ "$print_classpath" = 1 ]; then
  echo "$classpath"
  exit 0
fi

if [ -z "${DISPLAY:-}" ] && [ -z "${WAYLAND_DISPLAY:-}" ]; then
  echo "spy.sh: no display (DISPLAY is not set): lcm-spy is a window; use ssh -X, or" \
       "xvfb-run -a scripts/spy.sh ... (Debian package xvfb)" >&2
  exit 2
fi

args=()
if [ -n "$url" ]; then args+=(--lcm-url="$url"); fi
# preferIPv4Stack: LCM's UDP multicast (udpm://) joins IPv4 groups, as Debian's lcm-spy sets it.
exec java -Djava.net.preferIPv4Stack=true -ea -cp "$classpath" lcm.spy.Spy "${args[@]}"
