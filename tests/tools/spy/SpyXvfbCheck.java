package lcmloc.spytest;

import java.awt.Frame;
import java.awt.Rectangle;
import java.awt.Robot;
import java.awt.image.BufferedImage;
import java.io.File;
import java.lang.reflect.Constructor;
import java.lang.reflect.Field;
import java.lang.reflect.Method;
import java.util.List;
import java.util.Map;

import javax.imageio.ImageIO;
import javax.swing.Action;
import javax.swing.SwingUtilities;

import java.awt.Color;

import lcm.spy.ChannelData;
import lcm.spy.Spy;
import lcm.spy.SpyPlugin;

/**
 * Under an X server (Xvfb): starts lcm-spy in this JVM on URL, checks that it found
 * lcmloc.spy.PosePlugin on the CLASSPATH, waits for POSE on the bus, opens the pose view with
 * lcm-spy's own menu action (Spy.PluginStarter), lets it draw, takes a screenshot of its window and checks its pixels for
 * the track, the ellipse and the NIS band. Run as tools/spy.sh runs lcm-spy: the class path holds
 * LCM and this class only, the lcmloc jars are in the environment's CLASSPATH, where lcm-spy's
 * class discovery loads them; so this class names the plugin's classes only by their names.
 * Arguments: URL PNG_OUT. Exit 0 when all checks pass.
 */
public final class SpyXvfbCheck {
    private SpyXvfbCheck() {}

    @SuppressWarnings("unchecked")
    private static <T> T field(Object o, String name) throws ReflectiveOperationException {
        Field f = o.getClass().getDeclaredField(name);
        f.setAccessible(true);
        return (T) f.get(o);
    }

    private static Color colour(Class<?> panel, String name) throws ReflectiveOperationException {
        Field f = panel.getDeclaredField(name);
        f.setAccessible(true);
        return (Color) f.get(null);
    }

    /** Pixels within 40 (sum over R, G, B) of colour c. */
    private static int count(BufferedImage img, Color c) {
        int n = 0;
        for (int y = 0; y < img.getHeight(); ++y) {
            for (int x = 0; x < img.getWidth(); ++x) {
                int p = img.getRGB(x, y);
                int d = Math.abs(((p >> 16) & 0xff) - c.getRed()) + Math.abs(((p >> 8) & 0xff) - c.getGreen())
                    + Math.abs((p & 0xff) - c.getBlue());
                n += d <= 40 ? 1 : 0;
            }
        }
        return n;
    }

    private static void fail(String why) {
        System.out.println("FAIL: " + why);
        System.exit(1);
    }

    public static void main(String[] args) {
        try {
            check(args);
        } catch (Throwable e) { // lcm-spy's threads would keep the JVM alive
            e.printStackTrace();
            fail(e.toString());
        }
    }

    private static void check(String[] args) throws Exception {
        Spy spy = new Spy(args[0]);
        List<SpyPlugin> plugins = field(spy, "plugins");
        SpyPlugin pose = null;
        for (SpyPlugin p : plugins) {
            pose = p.getClass().getName().equals("lcmloc.spy.PosePlugin") ? p : pose;
        }
        if (pose == null) {
            fail("lcm-spy did not load PosePlugin from the CLASSPATH (plugins: " + plugins + ")");
        }
        Map<String, ChannelData> channels = field(spy, "channelMap");
        ChannelData cd = null;
        for (int i = 0; i < 300 && (cd == null || cd.nreceived < 20); ++i) {
            Thread.sleep(100);
            synchronized (channels) {
                cd = channels.get("POSE");
            }
        }
        if (cd == null || cd.nreceived < 20) {
            fail("no POSE seen by lcm-spy within 30 s");
        }
        if (!pose.canHandle(cd.fingerprint)) {
            fail("the plugin does not offer itself for POSE (fingerprint " + cd.fingerprint + ")");
        }
        final ChannelData channel = cd;
        final SpyPlugin plugin = pose;
        // What lcm-spy's right-click menu item runs: a window with a desktop, the plugin's action.
        Constructor<?> make = Class.forName("lcm.spy.Spy$PluginStarter")
            .getConstructor(Spy.class, SpyPlugin.class, ChannelData.class);
        make.setAccessible(true);
        Object starter = make.newInstance(spy, plugin, channel);
        Method getAction = starter.getClass().getMethod("getAction");
        getAction.setAccessible(true);
        Action open = (Action) getAction.invoke(starter);
        SwingUtilities.invokeAndWait(() -> open.actionPerformed(null));
        Thread.sleep(5000);
        Frame view = null;
        for (Frame f : Frame.getFrames()) {
            if (f.isVisible() && f.getTitle().equals(channel.name)) {
                view = f;
            }
        }
        if (view == null) {
            fail("no pose view window");
        }
        view.toFront();
        Thread.sleep(500);
        Rectangle r = view.getBounds();
        BufferedImage shot = new Robot().createScreenCapture(r);
        ImageIO.write(shot, "png", new File(args[1]));
        Class<?> panel = Class.forName("lcmloc.spy.PosePanel", true, pose.getClass().getClassLoader());
        int track = count(shot, colour(panel, "TRACK"));
        int ellipse = count(shot, colour(panel, "ELLIPSE"));
        int band = count(shot, colour(panel, "BAND"));
        System.out.println("screenshot " + r.width + "x" + r.height + ": track " + track + ", ellipse "
            + ellipse + ", band " + band + " pixels (" + args[1] + ")");
        if (track < 100 || ellipse < 60 || band < 500) {
            fail("the screenshot lacks the track, the ellipse or the NIS band");
        }
        System.exit(0);
    }
}
