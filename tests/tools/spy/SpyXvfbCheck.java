package lcmloc.spy;

import java.awt.Frame;
import java.awt.Rectangle;
import java.awt.Robot;
import java.awt.image.BufferedImage;
import java.io.File;
import java.lang.reflect.Field;
import java.util.List;
import java.util.Map;

import javax.imageio.ImageIO;
import javax.swing.SwingUtilities;

import lcm.spy.ChannelData;
import lcm.spy.Spy;
import lcm.spy.SpyPlugin;

/**
 * Under an X server (Xvfb): starts lcm-spy in this JVM on URL, checks that it found PosePlugin on
 * the CLASSPATH, waits for POSE on the bus, opens the pose view as lcm-spy's menu does, lets it
 * draw, takes a screenshot of its window and checks its pixels for the track and the ellipse.
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

    private static void fail(String why) {
        System.out.println("FAIL: " + why);
        System.exit(1);
    }

    public static void main(String[] args) throws Exception {
        Spy spy = new Spy(args[0]);
        List<SpyPlugin> plugins = field(spy, "plugins");
        SpyPlugin pose = null;
        for (SpyPlugin p : plugins) {
            pose = p instanceof PosePlugin ? p : pose;
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
        SwingUtilities.invokeAndWait(() -> plugin.getAction(null, channel).actionPerformed(null));
        Thread.sleep(5000);
        Frame view = null;
        for (Frame f : Frame.getFrames()) {
            if (f.isVisible() && f.getTitle().startsWith("lcmloc pose view")) {
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
        int track = PoseModelTest.count(shot, PosePanel.TRACK);
        int ellipse = PoseModelTest.count(shot, PosePanel.ELLIPSE);
        int band = PoseModelTest.count(shot, PosePanel.BAND);
        System.out.println("screenshot " + r.width + "x" + r.height + ": track " + track + ", ellipse "
            + ellipse + ", band " + band + " pixels (" + args[1] + ")");
        if (track < 100 || ellipse < 60 || band < 500) {
            fail("the screenshot lacks the track, the ellipse or the NIS band");
        }
        System.exit(0);
    }
}
