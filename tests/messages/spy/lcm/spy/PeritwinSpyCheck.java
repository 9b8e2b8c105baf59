// The check of the lcm-spy test (test_spy.cpp), run inside scripts/spy.sh's lcm-spy: a Spy plugin
// (Spy instantiates every SpyPlugin on its class path, here through $CLASSPATH), in package
// lcm.spy to reach the viewer's sparklines. It does nothing unless $PERITWIN_SPY_CHECK_TYPES is
// set. Then, on its own thread, while PeritwinSpyPublish sends one message per type:
//
//  1. class discovery: lcm-spy's LCMTypeDatabase (lcm.util.ClassDiscoverer over the class path)
//     finds peritwin_msgs.<type> by its LCM_FINGERPRINT, for every type named;
//  2. Spy's channel table (the window "LCM Spy", read as the user sees it) lists channel
//     $PERITWIN_SPY_CHECK_PREFIX<type> with type <type>, messages received and 0 undecodable;
//  3. a double-click on each row opens the message viewer (ObjectPanel: jchart2d's ITrace2D),
//     which paints the message's numbers with their sparklines;
//  4. a plot window (ZoomableChartScrollWheel, a jchart2d Chart2D) opens for one number of each.
//
// Anything thrown on the way, an uncaught exception in any thread (the event thread included)
// and any line with "Exception" or "Error" printed by Spy fail the check. It prints
// "spy-check: OK" and exits 0, or one "spy-check: FAIL ..." line per failure and exits 1; after
// $PERITWIN_SPY_CHECK_SECONDS (default 60) it fails with what is still missing.
package lcm.spy;

import java.awt.Component;
import java.awt.Container;
import java.awt.Frame;
import java.awt.Rectangle;
import java.awt.event.ActionEvent;
import java.awt.event.MouseEvent;
import java.io.OutputStream;
import java.io.PrintStream;
import java.lang.reflect.Field;
import java.util.ArrayList;
import java.util.Collections;
import java.util.List;
import java.util.Map;
import java.util.TreeMap;
import java.util.concurrent.atomic.AtomicReference;

import javax.swing.AbstractAction;
import javax.swing.Action;
import javax.swing.JDesktopPane;
import javax.swing.JFrame;
import javax.swing.JTable;
import javax.swing.SwingUtilities;

public final class PeritwinSpyCheck implements SpyPlugin {
  private static boolean started = false;
  private static final List<String> failures = Collections.synchronizedList(new ArrayList<>());
  private static PrintStream out;

  public PeritwinSpyCheck() {
    final String types = System.getenv("PERITWIN_SPY_CHECK_TYPES");
    synchronized (PeritwinSpyCheck.class) {
      if (types == null || started) return;
      started = true;
    }
    out = System.out;
    // Spy and its viewer report their exceptions on stdout (ObjectPanel.paintRecurse,
    // Spy.messageReceived) and go on: such a line is a failure too.
    System.setOut(watching(System.out));
    System.setErr(watching(System.err));
    Thread.setDefaultUncaughtExceptionHandler(
        (thread, e) -> fail("uncaught in thread " + thread.getName() + ": " + e));
    final String prefix = System.getenv().getOrDefault("PERITWIN_SPY_CHECK_PREFIX", "");
    final double seconds =
        Double.parseDouble(System.getenv().getOrDefault("PERITWIN_SPY_CHECK_SECONDS", "60"));
    final Thread thread = new Thread(() -> {
      try {
        run(types.split(","), prefix, System.nanoTime() + (long) (seconds * 1e9));
      } catch (Throwable e) {
        fail("check aborted: " + e);
        e.printStackTrace(out);
      }
      finish();
    }, "peritwin-spy-check");
    thread.start();
  }

  @Override
  public boolean canHandle(long fingerprint) {
    return false;  // a double-click opens Spy's own viewer
  }

  @Override
  public Action getAction(JDesktopPane jdp, ChannelData cd) {
    return new AbstractAction("peritwin spy check") {
      @Override
      public void actionPerformed(ActionEvent e) {}
    };
  }

  static void log(String line) {
    out.println("spy-check: " + line);
    out.flush();
  }

  static void fail(String what) {
    failures.add(what);
    log("FAIL " + what);
  }

  static void finish() {
    if (failures.isEmpty()) {
      log("OK");
      System.exit(0);
    }
    log(failures.size() + " failure(s)");
    System.exit(1);
  }

  static PrintStream watching(PrintStream target) {
    return new PrintStream(new OutputStream() {
      private final StringBuilder line = new StringBuilder();

      @Override
      public synchronized void write(int b) {
        target.write(b);
        if (b != '\n') {
          line.append((char) b);
          return;
        }
        final String text = line.toString();
        line.setLength(0);
        if (!text.startsWith("spy-check: ") && (text.contains("Exception") || text.contains("Error"))) {
          fail("Spy printed: " + text);
        }
      }

      @Override
      public void flush() {
        target.flush();
      }
    }, true);
  }

  static boolean expired(long deadline) {
    return System.nanoTime() > deadline;
  }

  static void sleep() throws InterruptedException {
    Thread.sleep(100);
  }

  static <T> T onEdt(java.util.concurrent.Callable<T> what) throws Exception {
    final AtomicReference<T> result = new AtomicReference<>();
    final AtomicReference<Exception> error = new AtomicReference<>();
    SwingUtilities.invokeAndWait(() -> {
      try {
        result.set(what.call());
      } catch (Exception e) {
        error.set(e);
      }
    });
    if (error.get() != null) throw error.get();
    return result.get();
  }

  static <T extends Component> T find(Component root, Class<T> type) {
    if (type.isInstance(root)) return type.cast(root);
    if (root instanceof Container) {
      for (Component child : ((Container) root).getComponents()) {
        final T found = find(child, type);
        if (found != null) return found;
      }
    }
    return null;
  }

  static JFrame frameTitled(String title) {
    for (Frame f : Frame.getFrames()) {
      if (f instanceof JFrame && f.isVisible() && title.equals(f.getTitle())) return (JFrame) f;
    }
    return null;
  }

  // The channel table as the user sees it: channel -> {type, messages, undecodable}.
  static Map<String, String[]> table(JTable t) {
    final Map<String, String[]> rows = new TreeMap<>();
    for (int r = 0; r < t.getRowCount(); ++r) {
      final Object channel = t.getValueAt(r, 0);
      if (channel == null) continue;
      rows.put(channel.toString(), new String[] {String.valueOf(t.getValueAt(r, 1)),
                                                 String.valueOf(t.getValueAt(r, 2)),
                                                 String.valueOf(t.getValueAt(r, 7))});
    }
    return rows;
  }

  static void run(String[] types, String prefix, long deadline) throws Exception {
    // 1. Class discovery, the way Spy finds the class of a message: by its fingerprint.
    final LCMTypeDatabase db = new LCMTypeDatabase();
    for (String type : types) {
      final Class<?> cls;
      try {
        cls = Class.forName("peritwin_msgs." + type);
      } catch (ClassNotFoundException e) {
        fail("no class peritwin_msgs." + type + " on the class path (peritwin_msgs.jar stale?)");
        continue;
      }
      final long fingerprint = cls.getField("LCM_FINGERPRINT").getLong(null);
      if (db.getClassByFingerprint(fingerprint) != cls) {
        fail(String.format("LCMTypeDatabase does not find %s by its fingerprint %016x", type,
                           fingerprint));
      } else {
        log(String.format("discovered %s fingerprint %016x", type, fingerprint));
      }
    }

    // 2. Every channel in Spy's table, decoded.
    JFrame spyFrame = null;
    while ((spyFrame = frameTitled("LCM Spy")) == null) {
      if (expired(deadline)) {
        fail("no visible window \"LCM Spy\"");
        return;
      }
      sleep();
    }
    final JTable channels = find(spyFrame.getContentPane(), JTable.class);
    if (channels == null) {
      fail("no channel table in the \"LCM Spy\" window");
      return;
    }
    List<String> waiting;
    Map<String, String[]> rows;
    while (true) {
      rows = onEdt(() -> table(channels));
      waiting = new ArrayList<>();
      for (String type : types) {
        final String[] row = rows.get(prefix + type);
        if (row == null || Long.parseLong(row[1].trim()) < 2) waiting.add(prefix + type);
      }
      if (waiting.isEmpty()) break;
      if (expired(deadline)) {
        fail("channels not listed (with 2 messages) by Spy: " + waiting + "; listed: "
             + rows.keySet());
        return;
      }
      sleep();
    }
    for (String type : types) {
      final String[] row = rows.get(prefix + type);
      if (!row[0].equals(type)) fail(prefix + type + ": Spy shows type \"" + row[0] + "\"");
      if (!row[2].trim().equals("0")) fail(prefix + type + ": " + row[2] + " undecodable messages");
      log(prefix + type + " listed as " + row[0] + ", " + row[1].trim() + " messages, "
          + row[2].trim() + " undecodable");
    }

    // 3. and 4. The viewer of each channel, and a plot of one of its numbers.
    for (String type : types) {
      final String channel = prefix + type;
      try {
        onEdt(() -> {
          for (int r = 0; r < channels.getRowCount(); ++r) {
            if (channel.equals(channels.getValueAt(r, 0))) {
              final Rectangle cell = channels.getCellRect(r, 0, true);
              channels.dispatchEvent(new MouseEvent(channels, MouseEvent.MOUSE_CLICKED,
                                                    System.currentTimeMillis(), 0,
                                                    cell.x + 5, cell.y + cell.height / 2, 2, false,
                                                    MouseEvent.BUTTON1));
              return null;
            }
          }
          throw new IllegalStateException("row vanished");
        });
      } catch (Throwable e) {
        Throwable cause = e instanceof java.lang.reflect.InvocationTargetException ? e.getCause() : e;
        fail("double-click on " + channel + ": " + cause);
        continue;
      }
      ObjectPanel panel = null;
      ObjectPanel.SparklineData line = null;
      while (line == null) {
        final JFrame viewer = frameTitled(channel);
        panel = viewer != null ? find(viewer.getContentPane(), ObjectPanel.class) : null;
        if (panel != null) {
          final ObjectPanel p = panel;
          // A sparkline whose chart exists: drawn with a number (sorted, to be deterministic).
          line = onEdt(() -> {
            final Field chartField = ObjectPanel.SparklineData.class.getDeclaredField("chart");
            chartField.setAccessible(true);
            final TreeMap<String, ObjectPanel.SparklineData> drawn = new TreeMap<>();
            for (ObjectPanel.Section s : p.sections) {
              for (ObjectPanel.SparklineData d : s.sparklines.values()) {
                if (chartField.get(d) != null) drawn.put(d.name, d);
              }
            }
            return drawn.isEmpty() ? null : drawn.firstEntry().getValue();
          });
        }
        if (line != null) break;
        if (expired(deadline)) {
          fail(channel + ": " + (panel == null ? "no viewer window" : "no number drawn in the viewer"));
          break;
        }
        sleep();
      }
      if (line == null) continue;
      final ObjectPanel p = panel;
      final ObjectPanel.SparklineData d = line;
      final int before = onEdt(() -> p.chartData.getCharts().size());
      try {
        onEdt(() -> {
          p.displayDetailedChart(d, true, true);
          return null;
        });
      } catch (Throwable e) {
        fail(channel + ": plot of " + d.name + ": " + e);
        continue;
      }
      final int after = onEdt(() -> p.chartData.getCharts().size());
      final JFrame plot = frameTitled(d.name);
      if (after != before + 1 || plot == null) {
        fail(channel + ": no plot window for " + d.name);
      } else {
        log(channel + ": viewer open, plot of " + d.name + " open");
      }
    }
    // Let the open viewers and plots take some more messages and repaint.
    Thread.sleep(1000);
  }
}
