package lcmloc.spy;

import java.awt.Window;
import java.awt.event.ActionEvent;
import java.awt.event.WindowAdapter;
import java.awt.event.WindowEvent;
import java.beans.PropertyVetoException;
import java.io.IOException;
import java.nio.file.Path;
import java.nio.file.Paths;
import java.util.Collections;
import java.util.List;
import java.util.concurrent.atomic.AtomicBoolean;
import java.util.regex.Pattern;

import javax.swing.AbstractAction;
import javax.swing.Action;
import javax.swing.JDesktopPane;
import javax.swing.JFrame;
import javax.swing.JInternalFrame;
import javax.swing.SwingUtilities;
import javax.swing.Timer;
import javax.swing.event.InternalFrameAdapter;
import javax.swing.event.InternalFrameEvent;

import lcm.lcm.LCM;
import lcm.lcm.LCMDataInputStream;
import lcm.lcm.LCMSubscriber;
import lcm.spy.ChannelData;
import lcm.spy.SpyPlugin;
import lcmloc.pose_t;

/**
 * lcm-spy plugin for pose_t channels (right-click a POSE channel: "lcmloc pose view"). It draws
 * the track, the 3-sigma ellipse scaled to be visible, the map (markers, landmarks or beacons) of
 * the CSV named by the system property lcmloc.spy.map or the environment variable LCMLOC_SPY_MAP
 * (read once), the accepted and rejected decisions of GATE (lcmloc.spy.gate / LCMLOC_SPY_GATE)
 * and the NIS strip against its 95 % chi-square band. It subscribes through LCM.getSingleton(),
 * whose URL is LCM_DEFAULT_URL: tools/spy.sh sets it to lcm-spy's URL.
 */
public final class PosePlugin implements SpyPlugin {
    private static final int TRACK = 5000;
    private static final int MARKS = 500;
    private static final int NIS = 300;
    private static List<MapCsv.Element> map;
    private static String mapNote;

    @Override
    public boolean canHandle(long fingerprint) {
        return fingerprint == pose_t.LCM_FINGERPRINT;
    }

    @Override
    public Action getAction(JDesktopPane desktop, ChannelData cd) {
        return new AbstractAction("lcmloc pose view (track, 3\u03c3 ellipse, map, GATE, NIS)") {
            @Override
            public void actionPerformed(ActionEvent e) {
                open(desktop, cd);
            }
        };
    }

    static String setting(String property, String env, String fallback) {
        String v = System.getProperty(property);
        if (v == null || v.isEmpty()) {
            v = System.getenv(env);
        }
        return v == null || v.isEmpty() ? fallback : v;
    }

    private static synchronized void loadMap() {
        if (map != null) {
            return;
        }
        String file = setting("lcmloc.spy.map", "LCMLOC_SPY_MAP", "");
        map = Collections.emptyList();
        if (file.isEmpty()) {
            mapNote = "no map (tools/spy.sh --map FILE)";
            return;
        }
        try {
            Path path = Paths.get(file);
            map = MapCsv.read(path);
            mapNote = "map " + path.getFileName() + ": " + map.size() + " elements";
        } catch (IOException | IllegalArgumentException e) {
            mapNote = "map not read: " + e.getMessage();
            System.err.println("lcmloc pose view: " + mapNote);
        }
    }

    private static void open(JDesktopPane desktop, ChannelData cd) {
        loadMap();
        String gate = setting("lcmloc.spy.gate", "LCMLOC_SPY_GATE", "GATE");
        PoseModel model = new PoseModel(gate, TRACK, MARKS, NIS);
        if (cd.last instanceof pose_t) {
            model.add((pose_t) cd.last);
        }
        PosePanel panel = new PosePanel(model, cd.name + " + " + gate, map, mapNote);
        LCM lcm = LCM.getSingleton();
        LCMSubscriber sub = new LCMSubscriber() {
            @Override
            public void messageReceived(LCM l, String channel, LCMDataInputStream in) {
                try {
                    model.accept(channel, in);
                } catch (IOException e) {
                    System.err.println("lcmloc pose view: " + channel + ": " + e.getMessage());
                }
            }
        };
        String poseRegex = Pattern.quote(cd.name);
        String gateRegex = Pattern.quote(gate);
        lcm.subscribe(poseRegex, sub);
        lcm.subscribe(gateRegex, sub);
        Timer timer = new Timer(200, e -> panel.repaint());
        timer.start();
        AtomicBoolean closed = new AtomicBoolean();
        Runnable close = () -> {
            if (closed.compareAndSet(false, true)) {
                timer.stop();
                lcm.unsubscribe(poseRegex, sub);
                lcm.unsubscribe(gateRegex, sub);
            }
        };
        WindowAdapter onWindowClose = new WindowAdapter() {
            @Override
            public void windowClosing(WindowEvent e) {
                close.run();
            }

            @Override
            public void windowClosed(WindowEvent e) {
                close.run();
            }
        };
        String title = "lcmloc pose view: " + cd.name;
        if (desktop != null) {
            // lcm-spy's menu opens a 500x400 window holding desktop: grown to the view's size.
            JInternalFrame frame = new JInternalFrame(title, true, true, true, true);
            frame.setContentPane(panel);
            frame.pack();
            frame.addInternalFrameListener(new InternalFrameAdapter() {
                @Override
                public void internalFrameClosed(InternalFrameEvent e) {
                    close.run();
                }
            });
            desktop.add(frame);
            Window window = SwingUtilities.getWindowAncestor(desktop);
            if (window != null) {
                window.addWindowListener(onWindowClose);
                window.setSize(Math.max(window.getWidth(), frame.getWidth() + 40),
                    Math.max(window.getHeight(), frame.getHeight() + 60));
            }
            frame.setVisible(true);
            try {
                frame.setMaximum(true);
            } catch (PropertyVetoException e) {
                // stays at its packed size
            }
        } else {
            JFrame frame = new JFrame(title);
            frame.setDefaultCloseOperation(JFrame.DISPOSE_ON_CLOSE);
            frame.setContentPane(panel);
            frame.pack();
            frame.addWindowListener(onWindowClose);
            frame.setVisible(true);
        }
    }
}
