// The publisher of the lcm-spy test (test_spy.cpp): one message of every named peritwin_msgs type,
// each on channel PREFIX + type name, every 100 ms until killed or `seconds` have passed.
//
//   java -cp lcm.jar:peritwin_msgs.jar:DIR PeritwinSpyPublish URL PREFIX SECONDS TYPE...
//
// The messages are filled by reflection, so a new type needs no change here: every integer field is
// 2 and every variable-length array has 2 elements (so each count equals its array's length),
// strings are "spy-test", nested types are filled the same way, and every floating-point field
// takes the round number + 0.5 (a number that changes, for the plots).
import java.lang.reflect.Array;
import java.lang.reflect.Field;
import java.lang.reflect.Modifier;
import java.util.ArrayList;
import java.util.List;

import lcm.lcm.LCM;
import lcm.lcm.LCMEncodable;

public final class PeritwinSpyPublish {
  private static final int kCount = 2;

  public static void main(String[] args) {
    if (args.length < 4) {
      System.err.println("usage: PeritwinSpyPublish URL PREFIX SECONDS TYPE...");
      System.exit(2);
    }
    try {
      publish(args);
    } catch (Throwable e) {
      // Exit: LCM's threads would keep the JVM alive.
      e.printStackTrace();
      System.exit(1);
    }
    System.exit(0);
  }

  static void publish(String[] args) throws Exception {
    final List<Class<?>> types = new ArrayList<>();
    for (int i = 3; i < args.length; ++i) types.add(Class.forName("peritwin_msgs." + args[i]));
    final LCM lcm = new LCM(args[0]);
    final String prefix = args[1];
    final long end = System.nanoTime() + (long) (Double.parseDouble(args[2]) * 1e9);

    for (int round = 0; System.nanoTime() < end; ++round) {
      for (Class<?> type : types) {
        final Object message = make(type, round + 0.5);
        lcm.publish(prefix + type.getSimpleName(), (LCMEncodable) message);
      }
      if (round == 0) {
        System.out.println("published " + types.size() + " types");
        System.out.flush();
      }
      Thread.sleep(100);
    }
    lcm.close();
  }

  static Object make(Class<?> type, double value) throws Exception {
    final Object o = type.getConstructor().newInstance();
    for (Field f : type.getFields()) {
      final int mods = f.getModifiers();
      if (Modifier.isStatic(mods) || Modifier.isFinal(mods)) continue;
      final Object current = f.get(o);
      f.set(o, fill(f.getType(), current, value));
    }
    return o;
  }

  // A value of `type`; `current` is what the constructor put there (a fixed-size array keeps its
  // length).
  static Object fill(Class<?> type, Object current, double value) throws Exception {
    if (type == long.class) return (long) kCount;
    if (type == int.class) return kCount;
    if (type == short.class) return (short) kCount;
    if (type == byte.class) return (byte) kCount;
    if (type == boolean.class) return ((long) value) % 2 == 0;
    if (type == double.class) return value;
    if (type == float.class) return (float) value;
    if (type == String.class) return "spy-test";
    if (type.isArray()) {
      final int n = current != null ? Array.getLength(current) : kCount;
      final Object a = Array.newInstance(type.getComponentType(), n);
      for (int i = 0; i < n; ++i) {
        final Object element = current != null ? Array.get(current, i) : null;
        Array.set(a, i, fill(type.getComponentType(), element, value + i));
      }
      return a;
    }
    return make(type, value);
  }
}
